#include "engine/estimate/fit.hpp"
#include <cstdio>
#include <cmath>
using namespace drape;
using namespace drape::estimate;
int main(int argc, char** argv)
{
    std::string mode = argc > 1 ? argv[1] : "noise";
    if (mode == "records") {
        for (int i = 1; i <= 10; ++i) {
            char d[200]; std::snprintf(d, sizeof d, DRAPE_SHARED_DIR "/data/drape-lab/set-a/DL-A%02d", i);
            auto m = load_record(d);
            auto f = drape_features(m);
            std::printf("%s D=%.1f photoD=%.1f nodes=%g (%s) deepest-contour nodes=%d hem=%.1fmm rho=%.3f depths=%zu\n", m.id.c_str(), f.drape_coefficient_percent, m.photo_drape_coefficient_percent, f.node_count, m.node_source.c_str(), f.contours.back().node_count, m.hem_min_z*1e3, m.areal_density, f.contours.size()); for (auto& n : m.notes) std::printf("    %s\n", n.c_str());
            for (auto& c : f.contours) std::printf("   d=%.0fmm r=%.1fmm fold=%.2fmm cos2=%.2f cos4=%.2f n=%d |c|1..8=%.2f %.2f %.2f %.2f %.2f %.2f %.2f %.2f\n", c.depth_m*1e3, c.mean_radius_m*1e3, c.fold_rms_m*1e3, c.cos2_m*1e3, c.cos4_m*1e3, c.node_count,
              c.magnitudes_m[0]*1e3,c.magnitudes_m[1]*1e3,c.magnitudes_m[2]*1e3,c.magnitudes_m[3]*1e3,c.magnitudes_m[4]*1e3,c.magnitudes_m[5]*1e3,c.magnitudes_m[6]*1e3,c.magnitudes_m[7]*1e3);
        }
        return 0;
    }
    int grid = argc > 2 ? std::atoi(argv[2]) : 25;
    double bend = argc > 3 ? std::atof(argv[3]) : 1e-5;
    double bend2 = argc > 4 ? std::atof(argv[4]) : bend;
    cloth::FabricParams p; p[cloth::Param::BendWarp] = bend; p[cloth::Param::BendWeft] = bend2;
    MeasuredDrape like; like.contours = {{0.005, {}}, {0.01, {}}, {0.015, {}}, {0.02, {}}, {0.025, {}}, {0.03, {}}};
    for (int s = 1; s <= 4; ++s) {
        auto setup = like.setup(grid, s);
        auto r = cloth::simulate_drape(p, setup);
        auto f = drape_features(r, like);
        std::printf("seed %d D=%.2f nodes(shadow)=%d nodes(deep)=%g hem=%.1fmm t=%.2fs |", s, f.drape_coefficient_percent, r.metrics.node_count, f.node_count, f.hem_min_z*1e3, r.status.wall_seconds);
        for (auto& c : f.contours) std::printf(" %s r=%.2f f=%.2f c2=%.2f", c.closed?"C":"o", c.mean_radius_m*1e3, c.fold_rms_m*1e3, c.cos2_m*1e3);
        std::printf("\n");
    }
}
