#pragma once
// A triangle mesh as a collider (mannequin, table, any imported body).
//
// Closest points come from a bounding-volume hierarchy of axis-aligned boxes
// (median split on the longest axis), searched branch-and-bound, so a query
// costs O(log n) triangles rather than all of them. The inside/outside sign
// uses angle-weighted pseudo-normals at the closest feature (face, edge or
// vertex): J. A. Baerentzen and H. Aanaes, "Signed distance computation using
// the angle weighted pseudonormal", IEEE TVCG 11(3), 2005. It is exact for a
// closed, consistently oriented (outward) mesh at any distance, so it stays
// right at thin parts (fingers, table edges), where a face normal alone gives
// the wrong side near an edge.
//
// For an open mesh (a table top without underside) the sign means "which side
// of the nearest surface piece", which is what a one-sided contact needs.
#include "engine/cloth/colliders.hpp"
#include "engine/cloth/mesh.hpp"

#include <Eigen/Core>

#include <vector>

namespace drape::importers {

/// Closest point on the mesh to a query point.
struct ClosestPoint {
    Eigen::Vector3d point = Eigen::Vector3d::Zero(); ///< [m]
    double distance = 0;  ///< unsigned distance [m]
    int triangle = -1;    ///< index of the triangle holding the point
    Eigen::Vector3d barycentric = Eigen::Vector3d::Zero();
};

class MeshCollider final : public cloth::Collider {
public:
    /// `X` n x 3 [m], `F` m x 3 with outward (counter-clockwise seen from
    /// outside) winding. `offset` [m] moves the contact surface outward (a
    /// thickness of skin or padding); negative values are rejected. Vertices at
    /// equal positions are welded internally so that pseudo-normals see the
    /// connectivity. Throws ParameterError on an empty mesh, indices out of
    /// range, non-finite coordinates or a negative/non-finite offset.
    MeshCollider(const cloth::Positions& X, const cloth::Triangles& F, double offset = 0.0);

    /// Signed distance to the offset surface [m] (positive outside) and the
    /// outward normal. Returns false only when p is outside and farther than
    /// `band` [m] from the offset surface; a point inside is always answered,
    /// however deep, so a vertex pushed through by a large step is pulled back.
    bool query(const Eigen::Vector3d& p, double band, cloth::ContactSample& out) const override;
    std::string kind() const override { return "mesh"; }

    /// Closest point on the (un-offset) mesh, searching within `max_distance` [m]
    /// (infinity = everywhere). Returns false when no triangle is that close.
    bool closest_point(const Eigen::Vector3d& p, ClosestPoint& out,
                       double max_distance = std::numeric_limits<double>::infinity()) const;
    /// Signed distance to the un-offset mesh [m], positive outside.
    double signed_distance(const Eigen::Vector3d& p) const;

    double offset() const { return m_offset; }
    const cloth::Positions& vertices() const { return m_X; }
    const cloth::Triangles& triangles() const { return m_F; }
    int node_count() const { return static_cast<int>(m_nodes.size()); }
    /// Number of edges with other than two incident triangles (0 for a closed manifold).
    int open_or_nonmanifold_edges() const { return m_bad_edges; }

private:
    struct Node {
        Eigen::Vector3d lo, hi;
        int left = -1, right = -1; ///< children, or -1 for a leaf
        int begin = 0, end = 0;    ///< range in m_order for a leaf
    };
    int build(int begin, int end, std::vector<Eigen::Vector3d>& centroids);
    Eigen::Vector3d pseudo_normal(int tri, const Eigen::Vector3d& bary) const;

    cloth::Positions m_X;
    cloth::Triangles m_F;
    double m_offset = 0;
    std::vector<Node> m_nodes;
    std::vector<int> m_order;                   ///< triangle indices, leaves are ranges of it
    std::vector<Eigen::Vector3d> m_face_normal; ///< unit
    std::vector<Eigen::Vector3d> m_vertex_normal; ///< angle-weighted, unit
    std::vector<Eigen::Vector3d> m_edge_normal; ///< per (triangle, local edge k = (k, k+1)): sum of the adjacent face normals
    int m_bad_edges = 0;
};

} // namespace drape::importers
