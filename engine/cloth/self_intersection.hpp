#pragma once
// Exact self-intersection count of a triangle mesh: how many pairs of
// triangles that share no vertex intersect. A bounding-volume hierarchy finds
// the candidate pairs; each pair is decided by exact predicates.
//
// Exactness: coordinates are rounded to a 1 nm lattice (a 64-bit integer per
// coordinate; |x| must stay below 1000 m) and the orientation determinants are
// evaluated in 128-bit integer arithmetic, so every predicate is exact for the
// rounded geometry. The rounding moves a vertex by at most 0.5 nm, far below
// any distance that matters for cloth (contact offsets are 0.05-1 mm); what is
// counted is the intersection of the mesh as it is, to that resolution.
//
// Touching counts as intersecting (two triangles that share a single point
// but no vertex intersect); coplanar overlapping pairs count too.
#include "engine/cloth/mesh.hpp"

#include <utility>
#include <vector>

namespace drape::cloth {

struct SelfIntersections {
    long pairs = 0;                          ///< intersecting pairs of triangles that share no vertex
    long candidates = 0;                     ///< pairs whose bounding boxes overlap (tested exactly)
    std::vector<std::pair<int, int>> sample; ///< up to 32 of the intersecting pairs (triangle indices)
};

/// Counts the intersecting non-adjacent triangle pairs of (X, F). Throws
/// ParameterError on non-finite or out-of-range coordinates or bad indices.
SelfIntersections self_intersections(const Positions& X, const Triangles& F);

/// Exact test of two triangles given by their vertices (world units [m]).
/// Exposed for tests; the same predicates as self_intersections.
bool triangles_intersect(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& a2,
                         const Eigen::Vector3d& b0, const Eigen::Vector3d& b1, const Eigen::Vector3d& b2);

} // namespace drape::cloth
