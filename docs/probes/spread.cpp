// Probe: drape-to-drape spread of the phase-locked contour terms (a1, b1, a2, a4) at 10, 20, 30 mm, from flat vs on the
// n-fold branch (seeded crest angles; ANGLE=deg: every branch drape with one crest there, the flat drapes skipped).
// spread PRESET.json|truth N SEED0 NSEEDS [LAYING WAVINESS_M]   (truth: the slow test's synthetic fabric), grid 41.
#include "engine/estimate/measured.hpp"
#include "engine/cloth/drape.hpp"
#include "engine/fabric/preset.hpp"
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
using namespace drape; using namespace drape::estimate; using cloth::Param;
int main(int argc, char** argv) {
    // spread PRESET|truth NFOLD SEED0 NSEEDS [laying waviness_m]
    cloth::Material mat = [&] {
        if (std::string(argv[1]) == "truth") { cloth::FabricParams p; p[Param::BendWarp] = 1.5e-5; p[Param::BendWeft] = 6e-6; p[Param::Shear] = 20; p[Param::AreaDensity] = 0.18; return cloth::Material(p); }
        return fabric::load_fabric(argv[1]).material(); }();
    cloth::ModelOptions mo;
    if (std::string(argv[1]) != "truth") mo = fabric::load_fabric(argv[1]).model;
    const int n = std::atoi(argv[2]), s0 = std::atoi(argv[3]), ns = std::atoi(argv[4]);
    const double laying = argc > 5 ? std::atof(argv[5]) : 1.0, wav = argc > 6 ? std::atof(argv[6]) : -1;
    for (int mode = std::getenv("ANGLE") ? 1 : 0; mode < 2; ++mode) {
        double sum[4][3] = {}, sq[4][3] = {};
        for (int s = s0; s < s0 + ns; ++s) {
            cloth::DrapeSetup st; st.sample_diameter = 0.3; st.disc_diameter = 0.15; st.grid = 41; st.seed = s;
            if (mode == 1) st = cloth::on_fold_branch(st, n, cloth::kFoldBranchLift, std::getenv("ANGLE") ? std::atof(std::getenv("ANGLE")) * M_PI / 180 : std::numeric_limits<double>::quiet_NaN());
            else { st.laying_load = laying; if (wav >= 0) st.perturbation = wav; }
            auto r = cloth::simulate_drape(mat, st, {}, mo);
            std::printf("%s seed %d D %.1f nodes %d |", mode ? "branch" : "flat  ", s, r.metrics.drape_coefficient_percent, r.metrics.node_count);
            int di = 0;
            for (const auto& sl : r.slices) {
                int d = (int)std::lround(sl.depth_m * 1e3);
                if (d != 10 && d != 20 && d != 30) continue;
                if (!sl.profile.complete()) { std::printf(" d%d open", d); ++di; continue; }
                auto f = contour_features(sl.profile, sl.depth_m);
                double v[4] = {f.cos1_m * 1e3, f.sin1_m * 1e3, f.cos2_m * 1e3, f.cos4_m * 1e3};
                std::printf(" d%d a1 %+.2f b1 %+.2f a2 %+.2f a4 %+.2f |", d, v[0], v[1], v[2], v[3]);
                for (int q = 0; q < 4; ++q) { sum[q][di] += v[q]; sq[q][di] += v[q] * v[q]; }
                ++di;
            }
            std::printf("\n"); std::fflush(stdout);
        }
        std::printf("%s sd:", mode ? "branch" : "flat  ");
        const char* nm[4] = {"a1", "b1", "a2", "a4"};
        for (int di = 0; di < 3; ++di) { std::printf(" d%d", 10 * (di + 1)); for (int q = 0; q < 4; ++q) { double m = sum[q][di] / ns; std::printf(" %s %.2f", nm[q], std::sqrt(std::max(0.0, sq[q][di] / ns - m * m) * ns / (ns - 1))); } std::printf(" |"); }
        std::printf("\n");
    }
}
