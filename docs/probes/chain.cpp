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
#include <algorithm>
#include <cmath>
namespace drape::cloth {
Positions interpolate_positions(const ClothMesh& coarse, const Positions& xc, const ClothMesh& fine)
{
    const double cell = std::max(coarse.grid.hu, coarse.grid.hv);
    const Eigen::Vector2d lo = coarse.uv.colwise().minCoeff().transpose() - Eigen::Vector2d::Constant(cell);
    const Eigen::Vector2d hi = coarse.uv.colwise().maxCoeff().transpose() + Eigen::Vector2d::Constant(cell);
    const int nx = static_cast<int>((hi.x() - lo.x()) / cell) + 1, ny = static_cast<int>((hi.y() - lo.y()) / cell) + 1;
    std::vector<std::vector<int>> buckets(static_cast<std::size_t>(nx * ny));
    auto bucket_of = [&](double x, double y, int& bx, int& by) {
        bx = std::clamp(static_cast<int>((x - lo.x()) / cell), 0, nx - 1);
        by = std::clamp(static_cast<int>((y - lo.y()) / cell), 0, ny - 1);
    };
    for (int t = 0; t < coarse.F.rows(); ++t) {
        Eigen::Vector2d bmin = Eigen::Vector2d::Constant(1e300), bmax = -bmin;
        for (int c = 0; c < 3; ++c) {
            bmin = bmin.cwiseMin(coarse.uv.row(coarse.F(t, c)).transpose());
            bmax = bmax.cwiseMax(coarse.uv.row(coarse.F(t, c)).transpose());
        }
        int x0, y0, x1, y1;
        bucket_of(bmin.x(), bmin.y(), x0, y0);
        bucket_of(bmax.x(), bmax.y(), x1, y1);
        for (int by = y0; by <= y1; ++by)
            for (int bx = x0; bx <= x1; ++bx) buckets[static_cast<std::size_t>(bx + nx * by)].push_back(t);
    }
    Positions out(fine.vertex_count(), 3);
    for (int i = 0; i < fine.vertex_count(); ++i) {
        const Eigen::Vector2d p = fine.uv.row(i).transpose();
        int bx, by;
        bucket_of(p.x(), p.y(), bx, by);
        double best = -1e300;
        Eigen::Vector3d bestb(1, 0, 0);
        int bestt = -1;
        for (int r = 0; r <= 3 && (bestt < 0 || best < -1e-9); ++r) {
            for (int yy = by - r; yy <= by + r; ++yy)
                for (int xx = bx - r; xx <= bx + r; ++xx) {
                    if (xx < 0 || yy < 0 || xx >= nx || yy >= ny) continue;
                    if (std::max(std::abs(xx - bx), std::abs(yy - by)) != r) continue;
                    for (int t : buckets[static_cast<std::size_t>(xx + nx * yy)]) {
                        const Eigen::Vector2d a = coarse.uv.row(coarse.F(t, 0)), b = coarse.uv.row(coarse.F(t, 1)), c = coarse.uv.row(coarse.F(t, 2));
                        Eigen::Matrix2d T;
                        T << b - a, c - a;
                        const double det = T.determinant();
                        if (std::abs(det) < 1e-300) continue;
                        const Eigen::Vector2d l = T.inverse() * (p - a);
                        const Eigen::Vector3d bc(1 - l.x() - l.y(), l.x(), l.y());
                        if (bc.minCoeff() > best) {
                            best = bc.minCoeff();
                            bestb = bc;
                            bestt = t;
                        }
                    }
                }
        }
        if (bestt < 0) {
            out.row(i) = fine.X.row(i);
            continue;
        }
        out.row(i) = bestb(0) * xc.row(coarse.F(bestt, 0)) + bestb(1) * xc.row(coarse.F(bestt, 1)) + bestb(2) * xc.row(coarse.F(bestt, 2));
    }
    return out;
}
}
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
