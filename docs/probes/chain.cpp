#include <Eigen/Dense>
// Probe: denim (or any preset) drape from flat through a chosen chain of grid levels.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/solver.hpp"
#include "engine/fabric/preset.hpp"
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>
using namespace drape;
int main(int argc, char** argv) {
    // chain.cpp FABRIC corr(0/1) seed g1 g2 ... (first level from flat, each next from prolongation)
    auto p = fabric::load_fabric(argv[1]);
    cloth::ModelOptions mo = p.model;
    mo.bending_correction = std::atoi(argv[2]) != 0;
    const int seed = std::atoi(argv[3]);
    const auto mat = p.material();
    cloth::Positions prev; int prevg = 0;
    for (int a = 4; a < argc; ++a) {
        cloth::DrapeSetup s; s.sample_diameter = 0.3; s.disc_diameter = 0.15; s.grid = std::atoi(argv[a]); s.seed = seed; if (getenv("FOLDS")) s.fold_mode = atoi(getenv("FOLDS"));
        auto sys = cloth::make_drape_system(mat, s, mo);
        if (prevg) { auto cm = cloth::make_disc(0.3, prevg, 0.0); sys->x = cloth::interpolate_positions(cm, prev, sys->mesh()); }
        cloth::RestOptions ro; ro.residual = 1e-6; ro.max_newton = 3000;
        auto st = cloth::run_to_rest(*sys, ro);
        auto m = cloth::measure_drape(*sys, s);
        std::printf("wall %.2f grid %d: D %.2f nodes %d its %ld E %.6e amps", st.wall_seconds, s.grid, m.metrics.drape_coefficient_percent, m.metrics.node_count, st.newton_iterations, sys->potential_energy(sys->x));
        for (double x : m.metrics.node_amplitudes_m) std::printf(" %.0f", x * 1000);
        std::printf("\n"); std::fflush(stdout);
        prev = sys->x; prevg = s.grid;
    }
}
