// `drape kes-dc`: drape coefficient predicted from Kawabata (KES-FB) data with
// the Gider (2004) regression quoted in the seed paper, to compare with a photo D.
#include "cli/command.hpp"

#ifdef HAVE_DRAPE_CAPTURE
#include "engine/capture/kes.hpp"

#include <cstdio>

namespace {

int run_kes(const std::vector<std::string>& argv)
{
    using namespace drape;
    const std::set<std::string> flags = {"--2hb", "--miu", "--g", "--rt", "--wc", "--rc", "--t0", "--emc", "--w"};
    cli::Args a(argv, flags, {});
    if (!a.positionals().empty()) throw cli::UsageError("kes-dc takes no positional arguments");
    for (const auto& f : flags)
        if (!a.get(f)) throw cli::UsageError("missing " + f + " (all nine KES values are needed)");
    capture::KesValues k;
    k.two_hb = a.get_double("--2hb", 0);
    k.miu = a.get_double("--miu", 0);
    k.g = a.get_double("--g", 0);
    k.rt = a.get_double("--rt", 0);
    k.wc = a.get_double("--wc", 0);
    k.rc = a.get_double("--rc", 0);
    k.t0 = a.get_double("--t0", 0);
    k.emc = a.get_double("--emc", 0);
    k.w = a.get_double("--w", 0);
    std::printf("%.2f\n", capture::gider_drape_coefficient(k));
    return 0;
}

DRAPE_COMMAND({"kes-dc", "drape coefficient from KES-FB values (Gider 2004 regression)",
               "usage: drape kes-dc --2hb V --miu V --g V --rt V --wc V --rc V --t0 V --emc V --w V\n"
               "Prints DC [%] = 69.17 + 25.51 2HB - 35.69 MIU + 3.50 G + 0.00049 RT + 21.13 WC\n"
               "                - 0.492 RC - 13.04 T0 + 0.303 EMC + 0.51 W   (Gider 2004, seed paper 5.2)\n"
               "Inputs in the usual KES-FB units (the paper does not restate them):\n"
               "  --2hb  bending hysteresis 2HB        [gf cm/cm]\n"
               "  --miu  mean frictional coefficient   [-]\n"
               "  --g    shear rigidity G              [gf/(cm deg)]\n"
               "  --rt   tensile resilience RT         [%]\n"
               "  --wc   compressional energy WC       [gf cm/cm^2]\n"
               "  --rc   compressional resilience RC   [%]\n"
               "  --t0   thickness at 0.5 gf/cm^2 T0   [mm]\n"
               "  --emc  compressibility EMC           [%]\n"
               "  --w    areal weight W                [mg/cm^2] (= g/m^2 / 10)\n"
               "Use warp/weft means where KES gives two directions.",
               run_kes});

} // namespace
#endif
