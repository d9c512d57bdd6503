// Probe: laying pace. Rest at s0*g from flat (grid G), then at g from there; report D and folds.
#include <Eigen/Dense>
#include "engine/cloth/drape.hpp"
#include "engine/cloth/solver.hpp"
#include "engine/fabric/preset.hpp"
#include <cstdio>
#include <cstdlib>
using namespace drape;
int main(int argc, char** argv) {
    // ramp PRESET grid seed s0 [s0 ...]
    auto p = fabric::load_fabric(argv[1]);
    const int grid = std::atoi(argv[2]), seed = std::atoi(argv[3]);
    for (int a = 4; a < argc; ++a) {
        const double s0 = std::atof(argv[a]);
        cloth::DrapeSetup s; s.sample_diameter = 0.3; s.disc_diameter = 0.15; s.grid = grid; s.seed = seed;
        auto sys = cloth::make_drape_system(p.material(), s, p.model);
        const Eigen::Vector3d g = sys->model().gravity;
        cloth::RestOptions ro; ro.residual = 1e-6; ro.max_newton = 3000;
        long its = 0;
        if (s0 < 1) { sys->model().gravity = s0 * g; its += cloth::run_to_rest(*sys, ro).newton_iterations; }
        sys->model().gravity = g;
        auto st = cloth::run_to_rest(*sys, ro); its += st.newton_iterations;
        auto m = cloth::measure_drape(*sys, s);
        std::printf("%s s0 %.3f: D %.2f nodes %d its %ld %s\n", argv[1], s0, m.metrics.drape_coefficient_percent, m.metrics.node_count, its, st.converged() ? "" : "NOT AT REST");
        std::fflush(stdout);
    }
}
