#include "importers/garment_metrics.hpp"

#include "engine/cloth/self_intersection.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <map>

namespace drape::importers {

std::vector<std::vector<int>> boundary_loops(const cloth::Triangles& F, int vertex_count)
{
    // An edge used by one triangle is on the boundary; orient it as in that triangle.
    std::map<std::pair<int, int>, int> uses;
    for (Eigen::Index t = 0; t < F.rows(); ++t)
        for (int k = 0; k < 3; ++k) {
            const int a = F(t, k), b = F(t, (k + 1) % 3);
            ++uses[{std::min(a, b), std::max(a, b)}];
        }
    std::vector<int> next(static_cast<std::size_t>(vertex_count), -1);
    for (Eigen::Index t = 0; t < F.rows(); ++t)
        for (int k = 0; k < 3; ++k) {
            const int a = F(t, k), b = F(t, (k + 1) % 3);
            if (uses[{std::min(a, b), std::max(a, b)}] == 1) next[static_cast<std::size_t>(a)] = b;
        }
    std::vector<std::vector<int>> loops;
    std::vector<char> seen(static_cast<std::size_t>(vertex_count), 0);
    for (int s = 0; s < vertex_count; ++s) {
        if (next[static_cast<std::size_t>(s)] < 0 || seen[static_cast<std::size_t>(s)]) continue;
        std::vector<int> loop;
        int v = s;
        while (v >= 0 && !seen[static_cast<std::size_t>(v)]) {
            seen[static_cast<std::size_t>(v)] = 1;
            loop.push_back(v);
            v = next[static_cast<std::size_t>(v)];
        }
        if (v == s && loop.size() >= 3) loops.push_back(std::move(loop));
    }
    return loops;
}

std::vector<int> hem_loop(const cloth::Positions& X, const cloth::Triangles& F, const std::vector<char>& pinned)
{
    std::vector<int> best;
    double best_z = std::numeric_limits<double>::infinity();
    for (auto& loop : boundary_loops(F, static_cast<int>(X.rows()))) {
        const bool held = std::any_of(loop.begin(), loop.end(), [&](int v) {
            return static_cast<std::size_t>(v) < pinned.size() && pinned[static_cast<std::size_t>(v)];
        });
        if (held) continue;
        double z = 0;
        for (int v : loop) z += X(v, 2) / static_cast<double>(loop.size());
        if (z < best_z) {
            best_z = z;
            best = std::move(loop);
        }
    }
    return best;
}

GarmentMetrics garment_metrics(const cloth::Positions& X, const cloth::Triangles& F, const std::vector<char>& pinned,
                               const Mannequin* m, const Eigen::Vector2d& axis, const cloth::MetricOptions& opt)
{
    GarmentMetrics g;
    const std::vector<int> hem = hem_loop(X, F, pinned);
    if (!hem.empty()) {
        cloth::Polygon2 poly;
        g.hem_min_z_m = std::numeric_limits<double>::infinity();
        g.hem_max_z_m = -g.hem_min_z_m;
        for (int v : hem) {
            const Eigen::Vector2d p(X(v, 0) - axis.x(), X(v, 1) - axis.y());
            poly.push_back(p);
            g.hem_mean_radius_m += p.norm() / static_cast<double>(hem.size());
            g.hem_min_z_m = std::min(g.hem_min_z_m, X(v, 2));
            g.hem_max_z_m = std::max(g.hem_max_z_m, X(v, 2));
        }
        cloth::DrapeMetrics dm;
        dm.profile = cloth::radial_profile(poly, opt.samples);
        if (dm.profile.complete()) {
            dm.fourier = cloth::fourier_fit(dm.profile, opt.smoothing_harmonics);
            cloth::find_nodes(dm.profile, opt, dm);
            g.hem_fold_count = dm.node_count;
        }
    }
    if (m) {
        const Penetration p = body_penetration(*m, X);
        g.vertices_inside_body = p.inside;
        g.min_body_distance_m = p.min_distance;
    }
    g.self_intersections = cloth::self_intersections(X, F).pairs;
    return g;
}

} // namespace drape::importers
