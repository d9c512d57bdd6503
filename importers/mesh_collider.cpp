#include "importers/mesh_collider.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"
#include "importers/mesh_import.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace drape::importers {

namespace {

using Vec3 = Eigen::Vector3d;

/// Closest point on triangle abc to p (C. Ericson, Real-Time Collision
/// Detection, 2005, section 5.1.5). Barycentric components are exactly zero in
/// the vertex and edge regions, which is how the caller tells the feature.
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, Vec3& bary)
{
    const Vec3 ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) {
        bary = {1, 0, 0};
        return a;
    }
    const Vec3 bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) {
        bary = {0, 1, 0};
        return b;
    }
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        bary = {1 - v, v, 0};
        return a + v * ab;
    }
    const Vec3 cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) {
        bary = {0, 0, 1};
        return c;
    }
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double w = d2 / (d2 - d6);
        bary = {1 - w, 0, w};
        return a + w * ac;
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        bary = {0, 1 - w, w};
        return b + w * (c - b);
    }
    const double denom = 1.0 / (va + vb + vc);
    const double v = vb * denom, w = vc * denom;
    bary = {1 - v - w, v, w};
    return a + ab * v + ac * w;
}

double box_distance2(const Vec3& p, const Vec3& lo, const Vec3& hi)
{
    const Vec3 d = (lo - p).cwiseMax(p - hi).cwiseMax(0.0);
    return d.squaredNorm();
}

} // namespace

MeshCollider::MeshCollider(const cloth::Positions& X, const cloth::Triangles& F, double offset) : m_offset(offset)
{
    if (!std::isfinite(offset) || offset < 0)
        throw ParameterError("mesh collider: offset = " + format_double(offset) + " m must be finite and >= 0");
    if (X.rows() == 0 || F.rows() == 0)
        throw ParameterError("mesh collider: empty mesh (" + std::to_string(X.rows()) + " vertices, " +
                             std::to_string(F.rows()) + " triangles)");
    for (int i = 0; i < X.rows(); ++i)
        if (!X.row(i).allFinite())
            throw ParameterError("mesh collider: vertex " + std::to_string(i) + " has a non-finite coordinate");
    for (int t = 0; t < F.rows(); ++t)
        for (int k = 0; k < 3; ++k)
            if (F(t, k) < 0 || F(t, k) >= X.rows())
                throw ParameterError("mesh collider: triangle " + std::to_string(t) + " has vertex index " +
                                     std::to_string(F(t, k)) + " outside [0, " + std::to_string(X.rows()) + ")");
    m_X = X;
    m_F = F;
    weld_vertices(m_X, m_F);
    // Zero-area triangles have no normal and no angle; they add nothing to the surface.
    {
        cloth::Triangles G(m_F.rows(), 3);
        int m = 0;
        for (int t = 0; t < m_F.rows(); ++t) {
            const Vec3 a = m_X.row(m_F(t, 0)), b = m_X.row(m_F(t, 1)), c = m_X.row(m_F(t, 2));
            const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()});
            if ((b - a).cross(c - a).squaredNorm() > 1e-24 * scale * scale) G.row(m++) = m_F.row(t);
        }
        m_F = G.topRows(m);
    }
    if (m_F.rows() == 0) throw ParameterError("mesh collider: every triangle has zero area");

    const int nf = static_cast<int>(m_F.rows());
    const int nv = static_cast<int>(m_X.rows());
    m_face_normal.resize(static_cast<std::size_t>(nf));
    m_vertex_normal.assign(static_cast<std::size_t>(nv), Vec3::Zero());
    for (int t = 0; t < nf; ++t) {
        const int i[3] = {m_F(t, 0), m_F(t, 1), m_F(t, 2)};
        const Vec3 p[3] = {m_X.row(i[0]), m_X.row(i[1]), m_X.row(i[2])};
        const Vec3 n = (p[1] - p[0]).cross(p[2] - p[0]).normalized();
        m_face_normal[static_cast<std::size_t>(t)] = n;
        for (int k = 0; k < 3; ++k) {
            const Vec3 e1 = (p[(k + 1) % 3] - p[k]).normalized(), e2 = (p[(k + 2) % 3] - p[k]).normalized();
            const double angle = std::acos(std::clamp(e1.dot(e2), -1.0, 1.0));
            m_vertex_normal[static_cast<std::size_t>(i[k])] += angle * n;
        }
    }
    for (auto& n : m_vertex_normal)
        if (n.squaredNorm() > 0) n.normalize();

    // Edge pseudo-normal: the sum of the adjacent face normals (equal weights, pi each).
    std::unordered_map<std::uint64_t, std::pair<Vec3, int>> edges;
    edges.reserve(static_cast<std::size_t>(3 * nf));
    auto key = [](int a, int b) {
        return (static_cast<std::uint64_t>(std::min(a, b)) << 32) | static_cast<std::uint32_t>(std::max(a, b));
    };
    for (int t = 0; t < nf; ++t)
        for (int k = 0; k < 3; ++k) {
            auto& e = edges[key(m_F(t, k), m_F(t, (k + 1) % 3))];
            if (e.second == 0) e.first.setZero();
            e.first += m_face_normal[static_cast<std::size_t>(t)];
            ++e.second;
        }
    m_edge_normal.resize(static_cast<std::size_t>(3 * nf));
    for (int t = 0; t < nf; ++t)
        for (int k = 0; k < 3; ++k)
            m_edge_normal[static_cast<std::size_t>(3 * t + k)] = edges[key(m_F(t, k), m_F(t, (k + 1) % 3))].first;
    for (const auto& [k, e] : edges) m_bad_edges += e.second != 2;

    // BVH over triangle centroids.
    std::vector<Vec3> centroids(static_cast<std::size_t>(nf));
    for (int t = 0; t < nf; ++t)
        centroids[static_cast<std::size_t>(t)] =
            (m_X.row(m_F(t, 0)) + m_X.row(m_F(t, 1)) + m_X.row(m_F(t, 2))).transpose() / 3.0;
    m_order.resize(static_cast<std::size_t>(nf));
    for (int t = 0; t < nf; ++t) m_order[static_cast<std::size_t>(t)] = t;
    m_nodes.reserve(static_cast<std::size_t>(2 * nf / 2 + 2));
    build(0, nf, centroids);
}

int MeshCollider::build(int begin, int end, std::vector<Vec3>& centroids)
{
    const int id = static_cast<int>(m_nodes.size());
    m_nodes.emplace_back();
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    Vec3 clo = lo, chi = hi;
    for (int i = begin; i < end; ++i) {
        const int t = m_order[static_cast<std::size_t>(i)];
        for (int k = 0; k < 3; ++k) {
            const Vec3 v = m_X.row(m_F(t, k));
            lo = lo.cwiseMin(v);
            hi = hi.cwiseMax(v);
        }
        clo = clo.cwiseMin(centroids[static_cast<std::size_t>(t)]);
        chi = chi.cwiseMax(centroids[static_cast<std::size_t>(t)]);
    }
    m_nodes[static_cast<std::size_t>(id)].lo = lo;
    m_nodes[static_cast<std::size_t>(id)].hi = hi;
    constexpr int kLeaf = 4;
    if (end - begin <= kLeaf) {
        m_nodes[static_cast<std::size_t>(id)].begin = begin;
        m_nodes[static_cast<std::size_t>(id)].end = end;
        return id;
    }
    int axis = 0;
    (chi - clo).maxCoeff(&axis);
    const int mid = (begin + end) / 2;
    std::nth_element(m_order.begin() + begin, m_order.begin() + mid, m_order.begin() + end, [&](int a, int b) {
        return centroids[static_cast<std::size_t>(a)][axis] < centroids[static_cast<std::size_t>(b)][axis];
    });
    const int l = build(begin, mid, centroids);
    const int r = build(mid, end, centroids);
    m_nodes[static_cast<std::size_t>(id)].left = l;
    m_nodes[static_cast<std::size_t>(id)].right = r;
    return id;
}

bool MeshCollider::closest_point(const Vec3& p, ClosestPoint& out, double max_distance) const
{
    double best2 = std::isfinite(max_distance) ? max_distance * max_distance : std::numeric_limits<double>::infinity();
    bool found = false;
    int stack[128];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const Node& n = m_nodes[static_cast<std::size_t>(stack[--top])];
        if (box_distance2(p, n.lo, n.hi) > best2) continue;
        if (n.left < 0) {
            for (int i = n.begin; i < n.end; ++i) {
                const int t = m_order[static_cast<std::size_t>(i)];
                Vec3 bary;
                const Vec3 c = closest_on_triangle(p, m_X.row(m_F(t, 0)), m_X.row(m_F(t, 1)), m_X.row(m_F(t, 2)), bary);
                const double d2 = (p - c).squaredNorm();
                if (d2 < best2 || (!found && d2 <= best2)) {
                    best2 = d2;
                    found = true;
                    out.point = c;
                    out.triangle = t;
                    out.barycentric = bary;
                }
            }
            continue;
        }
        // Push the farther child first so the nearer one is searched first and
        // tightens the bound early.
        const Node& a = m_nodes[static_cast<std::size_t>(n.left)];
        const Node& b = m_nodes[static_cast<std::size_t>(n.right)];
        const double da = box_distance2(p, a.lo, a.hi), db = box_distance2(p, b.lo, b.hi);
        if (da <= db) {
            if (db <= best2) stack[top++] = n.right;
            if (da <= best2) stack[top++] = n.left;
        } else {
            if (da <= best2) stack[top++] = n.left;
            if (db <= best2) stack[top++] = n.right;
        }
    }
    if (found) out.distance = std::sqrt(best2);
    return found;
}

Vec3 MeshCollider::pseudo_normal(int tri, const Vec3& bary) const
{
    int zeros = 0, nonzero = -1, zero = -1;
    for (int k = 0; k < 3; ++k) {
        if (bary[k] == 0.0) {
            ++zeros;
            zero = k;
        } else {
            nonzero = k;
        }
    }
    if (zeros >= 2) return m_vertex_normal[static_cast<std::size_t>(m_F(tri, nonzero))];
    if (zeros == 1) // the edge opposite vertex `zero` runs from (zero+1) to (zero+2): local edge index zero+1
        return m_edge_normal[static_cast<std::size_t>(3 * tri + (zero + 1) % 3)];
    return m_face_normal[static_cast<std::size_t>(tri)];
}

double MeshCollider::signed_distance(const Vec3& p) const
{
    ClosestPoint cp;
    closest_point(p, cp);
    const Vec3 n = pseudo_normal(cp.triangle, cp.barycentric);
    return (p - cp.point).dot(n) >= 0 ? cp.distance : -cp.distance;
}

bool MeshCollider::query(const Vec3& p, double band, cloth::ContactSample& out) const
{
    const double reach = band + m_offset;
    // Far outside the bounding box: certainly outside and out of reach.
    if (std::isfinite(reach)) {
        const double d2 = box_distance2(p, m_nodes[0].lo, m_nodes[0].hi);
        if (d2 > reach * reach) {
            out.clearance = std::sqrt(d2) - reach;
            return false;
        }
    }
    // Otherwise search without a bound: a point deep inside the body must
    // still be answered (with its true negative distance), or a vertex that a
    // large step pushed through would feel no contact force at all.
    ClosestPoint cp;
    closest_point(p, cp);
    const Vec3 pn = pseudo_normal(cp.triangle, cp.barycentric);
    const Vec3 d = p - cp.point;
    const bool outside = d.dot(pn) >= 0;
    if (outside && cp.distance > reach) {
        out.clearance = cp.distance - reach;
        return false;
    }
    // The direction from the closest point is the exact gradient of the
    // distance; on the surface itself fall back to the pseudo-normal.
    if (cp.distance > 1e-12) {
        out.normal = outside ? Vec3(d / cp.distance) : Vec3(-d / cp.distance);
    } else {
        out.normal = pn.squaredNorm() > 0 ? pn.normalized() : m_face_normal[static_cast<std::size_t>(cp.triangle)];
    }
    out.distance = (outside ? cp.distance : -cp.distance) - m_offset;
    return true;
}

} // namespace drape::importers
