// Probe: an n-fold start with one crest at each given angle [rad] from the warp (DrapeSetup::fold_angle) on the slow
// test's synthetic fabric (warp 1.5e-5, weft 6e-6 N*m, shear 20 N/m, 180 g/m^2), grid 41, seed 3: the angle of the
// rest state's crests (the contours' n-th harmonic summed over depths), D and the cos 2theta term at 20 mm.
#include "engine/estimate/measured.hpp"
#include "engine/cloth/drape.hpp"
#include <cmath>
#include <cstdio>
#include <cstdlib>
using namespace drape; using namespace drape::estimate; using cloth::Param;
int main(int argc, char** argv) {
    cloth::FabricParams p; p[Param::BendWarp] = 1.5e-5; p[Param::BendWeft] = 6e-6; p[Param::Shear] = 20; p[Param::AreaDensity] = 0.18;
    const int n = std::atoi(argv[1]);
    for (int a = 2; a < argc; ++a) {
        const double ang = std::atof(argv[a]);
        cloth::DrapeSetup st; st.grid = 41; st.seed = 3; st = cloth::on_fold_branch(st, n, cloth::kFoldBranchLift, ang);
        auto r = cloth::simulate_drape(p, st);
        DrapeFeatures f;
        for (const auto& sl : r.slices) if (sl.profile.complete()) f.contours.push_back(contour_features(sl.profile, sl.depth_m));
        double A = 0, B = 0;
        for (const auto& c : f.contours) { A += c.series.a[static_cast<std::size_t>(n - 1)]; B += c.series.b[static_cast<std::size_t>(n - 1)]; }
        std::printf("n %d lift angle %.3f -> nodes %d, rest angle %.3f, D %.2f, a2(d20) %.2f mm\n", n, ang, r.metrics.node_count, std::atan2(B, A) / n, r.metrics.drape_coefficient_percent, f.contours.size() > 3 ? f.contours[3].cos2_m * 1e3 : 0.0);
    }
}
