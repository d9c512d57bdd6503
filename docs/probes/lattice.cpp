// Probe: is the 4-fold lock of the laid drapes the square lattice's?
//
//   lattice PRESET GRID SEED
//
// Drapes PRESET from flat (laid as the preset says) on the drapemeter
// (300/150 mm) three ways, at the mesh spacing of grid GRID:
//   grid  - the product's disc (square lattice, orthotropic grid model);
//   sqtri - the same square-lattice triangles through the general triangle
//           model (fibre-net membrane and per-triangle curvature stencils since
//           2026-12-01; edge springs and hinge bending before: no lattice-aligned
//           stencils);
//   rings - concentric rings of near-equilateral triangles (no 4-fold
//           symmetry; each ring turned by the golden angle), general model.
// sqtri against rings isolates the mesh: same model, same spacing.
#include <Eigen/Dense>

#include "engine/cloth/drape.hpp"
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/model.hpp"
#include "engine/cloth/solver.hpp"
#include "engine/fabric/preset.hpp"

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <vector>

using namespace drape;

namespace {

/// rim_factor < 1: the spacing shrinks to rim_factor h0 between 65 and 90 mm from the
/// centre (the bend over a 150 mm pedestal's rim and the folds' roots), tapering back to
/// h0 over 15 mm on either side (RIMGRADE=f in the environment). Since 2026-12-01 the
/// product's generator (cloth::make_ring_disc; drapemeter_rim_grading is this band for
/// any pedestal, `drape simulate --mesh rings`).
cloth::ClothMesh ring_disc(double diameter, int grid, double rim_factor = 1.0)
{
    return cloth::make_ring_disc(diameter, grid, cloth::RingGrading{0.065, 0.090, rim_factor, 0.015});
}

void drape_on(const char* label, cloth::ClothMesh mesh, const fabric::FabricPreset& p, const cloth::DrapeSetup& s)
{
    cloth::ModelOptions mo = p.model;
    // BSCALE=s: warp and weft bending times s (to make up for a model's bending
    // that the iso test measures off).
    cloth::FabricParams q = p.params;
    if (const char* b = std::getenv("BSCALE")) {
        q[cloth::Param::BendWarp] *= std::atof(b);
        q[cloth::Param::BendWeft] *= std::atof(b);
    }
    cloth::ClothModel model = cloth::make_model(mesh, q, mo);
    // The centre held on the axis as make_drape_system holds it (nearest vertex).
    int c = 0;
    for (int i = 0; i < mesh.vertex_count(); ++i)
        if (std::hypot(mesh.X(i, 0), mesh.X(i, 1)) < std::hypot(mesh.X(c, 0), mesh.X(c, 1))) c = i;
    const double k = model.total_mass() * model.gravity.norm() / 1e-4;
    model.anchors.push_back(cloth::HorizontalAnchor::at_vertex(c, Eigen::Vector3d(mesh.X(c, 0), mesh.X(c, 1), 0.0), k));
    const int nv = mesh.vertex_count();
    cloth::ClothSystem sys(std::move(mesh), std::move(model));
    cloth::place_on_drapemeter(sys, s);
    cloth::RestOptions ro;
    ro.max_newton = 3000;
    const auto st = cloth::rest_from_flat(sys, s, ro);
    const auto m = cloth::measure_drape(sys, s);
    std::printf("%-6s %5d vertices: D %.2f nodes %d %s, %ld Newton, %.1f s, amplitudes [mm]", label, nv, m.metrics.drape_coefficient_percent,
                m.metrics.node_count, st.converged() ? "at rest" : "NOT at rest", st.newton_iterations, st.wall_seconds);
    for (double a : m.metrics.node_amplitudes_m) std::printf(" %.0f", a * 1000);
    std::printf("\n");
    std::fflush(stdout);
}

} // namespace

int main(int argc, char** argv)
{
    if (argc < 4) {
        std::fprintf(stderr, "usage: lattice PRESET GRID SEED [grid|sqtri|rings|graded ...]\n");
        return 2;
    }
    const auto p = fabric::load_fabric(argv[1]);
    cloth::DrapeSetup s;
    s.sample_diameter = 0.3;
    s.disc_diameter = 0.15;
    s.grid = std::atoi(argv[2]);
    s.seed = static_cast<std::uint64_t>(std::atoi(argv[3]));
    s.laying_load = p.laying();
    if (argc > 4 && std::string(argv[4]) == "iso") {
        // Bending energy of a cylinder of curvature kappa whose axis is turned by
        // phi from the weft (bending along phi), no gravity: E / (area kappa^2 / 2)
        // against Bu cos^4 + 2 Bt cos^2 sin^2 + Bv sin^4 of an orthotropic plate.
        const double kappa = 0.5; // [1/m]
        for (const char* way : {"grid", "sqtri", "rings"}) {
            cloth::ClothMesh mesh = std::string(way) == "grid" ? cloth::make_disc(s.sample_diameter, s.grid, 0.0)
                                    : std::string(way) == "sqtri" ? [&] { auto g = cloth::make_disc(s.sample_diameter, s.grid, 0.0); return cloth::make_triangle_mesh(g.X, g.F); }()
                                                                  : ring_disc(s.sample_diameter, s.grid);
            cloth::ModelOptions mo = p.model;
            cloth::ClothModel model = cloth::make_model(mesh, p.params, mo);
            model.gravity.setZero();
            const double area = mesh.area();
            cloth::ClothSystem sys(std::move(mesh), std::move(model));
            std::printf("%-6s", way);
            for (int deg = 0; deg <= 90; deg += 15) {
                const double ph = deg * std::numbers::pi / 180;
                cloth::Positions X = sys.mesh().X;
                // The plane rolled onto the cylinder (an isometry: no stretch).
                const double R = 1 / kappa;
                for (int i = 0; i < X.rows(); ++i) {
                    const double t = X(i, 0) * std::cos(ph) + X(i, 1) * std::sin(ph);
                    const double dt = R * std::sin(t / R) - t;
                    X(i, 0) += dt * std::cos(ph);
                    X(i, 1) += dt * std::sin(ph);
                    X(i, 2) = R * (1 - std::cos(t / R));
                }
                std::printf("  %2d deg %.3g", deg, sys.potential_energy(X) / (0.5 * area * kappa * kappa));
            }
            std::printf("  [N*m]  (Bu %.3g Bv %.3g)\n", p.params[cloth::Param::BendWarp], p.params[cloth::Param::BendWeft]);
        }
        return 0;
    }
    std::vector<std::string> ways;
    for (int a = 4; a < argc; ++a) ways.emplace_back(argv[a]);
    if (ways.empty()) ways = {"grid", "sqtri", "rings"};
    for (const auto& w : ways) {
        if (w == "grid") {
            auto sys = cloth::make_drape_system(p.material(), s, p.model);
            cloth::RestOptions ro;
            ro.max_newton = 3000;
            const auto st = cloth::rest_from_flat(*sys, s, ro);
            const auto m = cloth::measure_drape(*sys, s);
            std::printf("%-6s %5d vertices: D %.2f nodes %d %s, %ld Newton, %.1f s, amplitudes [mm]", "grid", sys->vertex_count(),
                        m.metrics.drape_coefficient_percent, m.metrics.node_count, st.converged() ? "at rest" : "NOT at rest", st.newton_iterations,
                        st.wall_seconds);
            for (double a : m.metrics.node_amplitudes_m) std::printf(" %.0f", a * 1000);
            std::printf("\n");
        } else if (w == "sqtri") {
            const auto g = cloth::make_disc(s.sample_diameter, s.grid, 0.0);
            drape_on("sqtri", cloth::make_triangle_mesh(g.X, g.F), p, s);
        } else if (w == "rings") {
            drape_on("rings", ring_disc(s.sample_diameter, s.grid), p, s);
        } else if (w == "graded") {
            const double f = std::getenv("RIMGRADE") ? std::atof(std::getenv("RIMGRADE")) : 0.4;
            drape_on("graded", ring_disc(s.sample_diameter, s.grid, f), p, s);
        }
    }
}
