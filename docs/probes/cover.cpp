// Probe: the slow test's synthetic fabric (BW, BF, SH override warp, weft, shear) fitted at grid 41 from records drawn
// from flat with perturbation seeds argv[1..]; every fitted parameter's 95 % interval against the truth (TRACE=1: the
// evaluations; TERMS=1: the phase-locked terms and the record's harmonic magnitudes).
#include "engine/estimate/fit.hpp"
#include "tests/estimate/synthetic.hpp"
#include <cstdio>
#include <cstdlib>
using namespace drape; using namespace drape::estimate; using cloth::Param;
int main(int argc, char** argv) {
    cloth::FabricParams p;
    p[Param::BendWarp] = std::getenv("BW") ? std::atof(std::getenv("BW")) : 1.5e-5;
    p[Param::BendWeft] = std::getenv("BF") ? std::atof(std::getenv("BF")) : 6.0e-6;
    p[Param::Shear] = std::getenv("SH") ? std::atof(std::getenv("SH")) : 20;
    p[Param::AreaDensity] = 0.18;
    for (int a = 1; a < argc; ++a) {
        const std::uint64_t seed = std::strtoull(argv[a], nullptr, 10);
        auto rec = test::synthetic_record(p, test::drape_setup(0.3, 0.15, 41, seed), "synthetic-" + std::to_string(seed));
        FitOptions o; o.grid = 41; o.seed = 1;
        const FitResult r = fit_fabric({rec}, o);
        int all = 1;
        for (const auto& e : r.estimates) {
            if (e.role != "fitted" && e.role != "held" && e.role != "tied") continue;
            const bool in = e.lower95 <= p[e.id] && p[e.id] <= e.upper95;
            if (e.role != "held") all &= in;
            std::printf("seed %d %-14s %-6s truth %.3g fitted %.3g [%.3g, %.3g] %s\n", int(seed), e.key.c_str(), e.role.c_str(), p[e.id], e.value, e.lower95, e.upper95, in ? "in" : "OUT");
        }
        std::printf("seed %d ALL %s  D err %+.2f nodes meas %d err %+.2f chi2 %.1f/%d sims %ld | %s | %s\n", int(seed), all ? "in" : "OUT", r.records[0].dc_error_percent,
                    rec.node_count, r.records[0].node_error, r.chi2, r.dof, r.simulations, r.anisotropy.reason.c_str(), r.shear_hold.reason.c_str());
        if (std::getenv("TERMS")) {
            for (const auto& t : r.residuals) if (t.kind == "cos2" || t.kind == "cos4" || t.kind == "cos1" || t.kind == "sin1")
                std::printf("  %-5s depth %2.0f sim %+.2f meas %+.2f sigma %.2f mm\n", t.kind.c_str(), t.depth_m * 1e3, t.simulated * 1e3, t.measured * 1e3, t.sigma * 1e3);
            for (const auto& c : r.records[0].measured_features.contours) { std::printf("  |c_k| depth %2.0f:", c.depth_m * 1e3); for (std::size_t k = 0; k < 12 && k < c.magnitudes_m.size(); ++k) std::printf(" %.2f", c.magnitudes_m[k] * 1e3); std::printf("\n"); }
        }
        if (std::getenv("TRACE")) for (const auto& t : r.trace) { std::printf("  %2d %-8s %8.2f", t.evaluation, t.stage.c_str(), t.chi2); for (double c : t.coords) std::printf(" %.3f", c); std::printf("\n"); }
        std::fflush(stdout);
    }
}
