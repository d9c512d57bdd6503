#pragma once
// The fit: simulate the drapemeter with candidate parameters, compare with the
// measured records (objective.hpp), minimise (Levenberg-Marquardt on the exact
// rest-state sensitivities, or NLopt's CRS2 and BOBYQA), and estimate each
// parameter's uncertainty from the Jacobian of the whitened residuals at the
// optimum. The vocabulary (options, result, progress) is fit_types.hpp.
//
// Method after Kuzmina, Tamas, Halasz, Grof (the method paper, section 5.4): "the
// actual simulation parameters are defined by the minimum of the difference
// between the modeled and the measured geometry".
#include "engine/estimate/fit_types.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace drape::estimate {

/// One line for a progress display (`drape fit`, the demo): the stage and the work
/// done - "local evaluation 7 (at most 44), best chi2 33.0, 21 simulations" in
/// the search, "from flat: 18 simulations, best chi2 33.0; the preset from flat on
/// the fit's grid and the finer one" after it (" (done)" once drawn).
std::string fit_progress_line(const FitProgress& p);

/// Fits one parameter set to all records jointly (repeats of the same fabric,
/// other sample/disc sizes). Throws ParameterError on no records or bad options.
/// Cancellation (options.cancel) returns the best point so far with cancelled = true.
FitResult fit_fabric(const std::vector<MeasuredDrape>& records, const FitOptions& options);

/// Buckling length (cloth::Param::BucklingLength) a fit holds when nothing else
/// is given [m]: the starter fabrics' documented typical value. A drape test
/// alone does not tell it (docs/decisions/0003-buckling-length-7-5mm.md), but with it
/// the fitted bending carries over between meshes (DL-A04: from flat at grids
/// 41/61/81 D 34.0/33.7/33.5 % with it, 35.9/28.6/26.3 % with the seed's
/// membrane, l = 0), so `drape fit` holds it here rather than at the seed's 0.
inline constexpr double kTypicalBucklingLength = 0.0075;

/// Where `--model slack` starts cloth::Param::CompressionSlack when the start has
/// none: 1 %, the middle of its fit range (a fit cannot leave 0, where the
/// parameter's relative step is none).
inline constexpr double kSlackFitStart = 0.01;

/// The start `drape fit` uses without --start: the parameter table's defaults
/// with buckling_length_m = kTypicalBucklingLength.
cloth::FabricParams default_fit_start();

/// The options `drape fit` fits with when no flag changes them, one place for
/// the CLI, the demo's fits and bench_fit: grid 41, the crest-corrected bending
/// stencils, the lab's laying (cloth::kLabLaying) and waviness
/// (cloth::kLabWaviness), the preset also draped from flat at grid 61 and calibrated from
/// flat, the start default_fit_start(). The library's FitOptions{} keeps the
/// plain engine (no laying, no drapes from flat, no calibration) for tests.
FitOptions drape_fit_defaults();

/// A record against a preset's free strips (cloth/elastica.hpp): the bending
/// whose free radial strips drape to the record's D, and the D the preset's own
/// strips drape to at its set-up (the mean of a warp and a weft strip); `below`
/// when those lie more than kFreeStripMarginPoints above the record's D - no drape
/// of the preset's bending reaches it. NaN / false without a D in (0, 100) or a
/// declared weight.
struct FreeStripCheck {
    double bound_Nm = std::numeric_limits<double>::quiet_NaN();
    double preset_dc_percent = std::numeric_limits<double>::quiet_NaN();
    bool below = false;
};
FreeStripCheck free_strip_check(const MeasuredDrape& m, double measured_dc_percent, const cloth::FabricParams& p);

/// free_strip_check for every record of a fit, at its preset (RecordFit::free_strip_*,
/// below_free_strips); fit_fabric calls it on its result.
void check_free_strips(FitResult& r);

/// Preset JSON of a fit: parameters plus provenance (records, date, model,
/// grid, seeds), fit quality, intervals, correlations and the residual analysis.
nlohmann::json fit_to_json(const FitResult& r);

} // namespace drape::estimate
