// `drape kes-dc`: drape coefficient predicted from Kawabata (KES-FB) data with
// the Gider (2004) regression quoted in the seed paper, to compare with a photo D.
#include "cli/command.hpp"

#ifdef HAVE_DRAPE_CAPTURE
#include "engine/capture/kes.hpp"
#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <cmath>

#include <cstdio>

namespace cmd_kes {

/// Physical ranges of the KES-FB values (the regression's inputs), in their units.
struct KesInput {
    const char* flag;
    double drape::capture::KesValues::*field;
    double lo, hi;
    const char* unit;
};
const KesInput kInputs[] = {
    {"--2hb", &drape::capture::KesValues::two_hb, 0, 10, "gf cm/cm"},
    {"--miu", &drape::capture::KesValues::miu, 0, 2, ""},
    {"--g", &drape::capture::KesValues::g, 0, 100, "gf/(cm deg)"},
    {"--rt", &drape::capture::KesValues::rt, 0, 100, "%"},
    {"--wc", &drape::capture::KesValues::wc, 0, 10, "gf cm/cm^2"},
    {"--rc", &drape::capture::KesValues::rc, 0, 100, "%"},
    {"--t0", &drape::capture::KesValues::t0, 0.001, 20, "mm"},
    {"--emc", &drape::capture::KesValues::emc, 0, 100, "%"},
    {"--w", &drape::capture::KesValues::w, 0.1, 200, "mg/cm^2"},
};

int run_kes(const std::vector<std::string>& argv)
{
    using namespace drape;
    std::set<std::string> flags;
    for (const auto& in : kInputs) flags.insert(in.flag);
    cli::Args a(argv, flags, {});
    if (!a.positionals().empty()) throw cli::UsageError("kes-dc takes no positional arguments");
    for (const auto& f : flags)
        if (!a.get(f)) throw cli::UsageError("missing " + f + " (all nine KES values are needed)");
    capture::KesValues k;
    for (const auto& in : kInputs) k.*in.field = a.get_double_in(in.flag, 0, in.lo, in.hi, in.unit);
    const double dc = capture::gider_drape_coefficient(k);
    // A regression extrapolated far from the fabrics it was fitted on can leave
    // [0, 100] %, where no drape coefficient lies: refused, not printed.
    if (!std::isfinite(dc) || dc < 0 || dc > 100)
        throw ParameterError("the Gider (2004) regression gives D = " + format_value(dc) +
                             " % for these KES values, outside [0, 100] %: the values are outside the range of fabrics it was fitted on");
    std::printf("%.2f\n", dc);
    return 0;
}

DRAPE_COMMAND({"kes-dc", "drape coefficient from KES-FB values (Gider 2004 regression)",
               "usage: drape kes-dc --2hb V --miu V --g V --rt V --wc V --rc V --t0 V --emc V --w V\n"
               "Prints DC [%] = 69.17 + 25.51 2HB - 35.69 MIU + 3.50 G + 0.00049 RT + 21.13 WC\n"
               "                - 0.492 RC - 13.04 T0 + 0.303 EMC + 0.51 W   (Gider 2004, seed paper 5.2)\n"
               "Inputs in the usual KES-FB units (the paper does not restate them), each in its physical range:\n"
               "  --2hb  bending hysteresis 2HB        [gf cm/cm]     0 .. 10\n"
               "  --miu  mean frictional coefficient   [-]            0 .. 2\n"
               "  --g    shear rigidity G              [gf/(cm deg)]  0 .. 100\n"
               "  --rt   tensile resilience RT         [%]            0 .. 100\n"
               "  --wc   compressional energy WC       [gf cm/cm^2]   0 .. 10\n"
               "  --rc   compressional resilience RC   [%]            0 .. 100\n"
               "  --t0   thickness at 0.5 gf/cm^2 T0   [mm]           0.001 .. 20\n"
               "  --emc  compressibility EMC           [%]            0 .. 100\n"
               "  --w    areal weight W                [mg/cm^2]      0.1 .. 200 (= g/m^2 / 10)\n"
               "Use warp/weft means where KES gives two directions. A D outside [0, 100] % (the regression\n"
               "extrapolated beyond the fabrics it was fitted on) is refused with exit 1.",
               run_kes});

} // namespace cmd_kes
#endif
