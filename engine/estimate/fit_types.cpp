// The fit's options by name (fit_types.hpp): the fold branch, method, bending tie
// and shear hold as the CLI's flags and the preset JSON spell them.
#include "engine/estimate/fit_types.hpp"

#include "engine/core/error.hpp"

namespace drape::estimate {

const char* to_string(Stage s)
{
    switch (s) {
    case Stage::Start: return "start";
    case Stage::Scan: return "scan";
    case Stage::Global: return "global";
    case Stage::Local: return "local";
    case Stage::Mirror: return "mirror";
    case Stage::Jacobian: return "jacobian";
    case Stage::Shear: return "shear";
    case Stage::Spread: return "spread";
    case Stage::Uncertainty: return "uncertainty";
    case Stage::FromFlat: return "from flat";
    case Stage::FromFlatFoldCount: return "from flat, fold count";
    case Stage::FromFlatCalibrated: return "from flat, calibrated";
    case Stage::Effects: return "effects";
    case Stage::PresetAsSaved: return "preset as saved";
    case Stage::Done: return "done";
    }
    return "?";
}

std::string to_string(FoldBranch b) { return b == FoldBranch::Measured ? "measured" : b == FoldBranch::Mixed ? "mixed" : "random"; }

FoldBranch parse_fold_branch(const std::string& name)
{
    if (name == "measured") return FoldBranch::Measured;
    if (name == "random") return FoldBranch::Random;
    if (name == "mixed") return FoldBranch::Mixed;
    throw ParameterError("branch: '" + name + "' is not one of measured, random, mixed");
}

std::string to_string(FitMethod m) { return m == FitMethod::Sensitivity ? "lm" : "nlopt"; }

FitMethod parse_fit_method(const std::string& name)
{
    if (name == "lm") return FitMethod::Sensitivity;
    if (name == "nlopt") return FitMethod::Nlopt;
    throw ParameterError("method: '" + name + "' is not one of lm, nlopt");
}

std::string to_string(BendingTie t) { return t == BendingTie::Auto ? "auto" : t == BendingTie::Free ? "free" : "tied"; }

BendingTie parse_bending_tie(const std::string& name)
{
    if (name == "auto") return BendingTie::Auto;
    if (name == "free") return BendingTie::Free;
    if (name == "tied") return BendingTie::Tied;
    throw ParameterError("bending: '" + name + "' is not one of auto, free, tied");
}

std::string to_string(ShearHold h) { return h == ShearHold::Auto ? "auto" : "free"; }

ShearHold parse_shear_hold(const std::string& name)
{
    if (name == "auto") return ShearHold::Auto;
    if (name == "free") return ShearHold::Free;
    throw ParameterError("shear: '" + name + "' is not one of auto, free");
}

} // namespace drape::estimate
