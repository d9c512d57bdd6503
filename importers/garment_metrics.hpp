#pragma once
// What a person compares between two drapes of one garment: how far the hem
// stands out from the body's axis, how many folds it makes, whether the cloth
// stays outside the body and out of itself. Measured by the drapemeter's own
// node counter on the hem's r(theta), so a fold means the same everywhere.
#include "importers/body.hpp"

#include "engine/cloth/metrics.hpp"

#include <vector>

namespace drape::importers {

/// Closed boundary loops of a triangle mesh, each in order along the loop.
std::vector<std::vector<int>> boundary_loops(const cloth::Triangles& F, int vertex_count);

/// The hem: the boundary loop with the lowest mean height among the loops that
/// hold no pinned vertex (a waistband is pinned). Empty when there is none.
std::vector<int> hem_loop(const cloth::Positions& X, const cloth::Triangles& F, const std::vector<char>& pinned);

struct GarmentMetrics {
    double hem_mean_radius_m = 0;  ///< mean horizontal distance of the hem vertices from the axis
    double hem_min_z_m = 0, hem_max_z_m = 0; ///< [m]
    int hem_fold_count = 0;        ///< crests of the hem's r(theta) (cloth::find_nodes)
    int vertices_inside_body = 0;
    double min_body_distance_m = 0; ///< signed: negative = a vertex inside the body
    long self_intersections = 0;   ///< intersecting non-adjacent triangle pairs (exact)
};

/// Metrics of garment positions X on body `m`; `axis` is the body's vertical
/// axis (x, y) [m], e.g. the waist centre.
GarmentMetrics garment_metrics(const cloth::Positions& X, const cloth::Triangles& F, const std::vector<char>& pinned,
                               const Mannequin* m, const Eigen::Vector2d& axis,
                               const cloth::MetricOptions& opt = cloth::MetricOptions{});

} // namespace drape::importers
