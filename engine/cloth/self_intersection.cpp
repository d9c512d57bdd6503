#include "engine/cloth/self_intersection.hpp"

#include "engine/cloth/bvh.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>

namespace drape::cloth {

namespace {

using i64 = std::int64_t;
__extension__ typedef __int128 i128; // GCC and Clang; __extension__ keeps -Wpedantic quiet
using P = std::array<i64, 3>; ///< a point on the 1 nm lattice

constexpr double kLattice = 1e-9;  ///< [m]
constexpr double kMaxCoord = 100.0; ///< [m]: keeps every determinant inside 128 bits (see the header)

P snap(const Eigen::Vector3d& x)
{
    return {static_cast<i64>(std::llround(x.x() / kLattice)), static_cast<i64>(std::llround(x.y() / kLattice)),
            static_cast<i64>(std::llround(x.z() / kLattice))};
}

int sign(i128 v) { return (v > 0) - (v < 0); }

/// Sign of the volume of (a, b, c, d): > 0 when d is above the plane of a, b, c
/// (counter-clockwise seen from above). Exact.
int orient3d(const P& a, const P& b, const P& c, const P& d)
{
    const i128 ax = a[0] - d[0], ay = a[1] - d[1], az = a[2] - d[2];
    const i128 bx = b[0] - d[0], by = b[1] - d[1], bz = b[2] - d[2];
    const i128 cx = c[0] - d[0], cy = c[1] - d[1], cz = c[2] - d[2];
    return sign(ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx));
}

/// Sign of the 2-D orientation of (a, b, c) in the coordinates (u, v). Exact.
int orient2d(const P& a, const P& b, const P& c, int u, int v)
{
    const i128 abx = b[u] - a[u], aby = b[v] - a[v], acx = c[u] - a[u], acy = c[v] - a[v];
    return sign(abx * acy - aby * acx);
}

/// The two coordinates to project a plane with normal n on (dropping the
/// dominant one, so the projection keeps the plane's shapes non-degenerate).
std::pair<int, int> projection(const P& a, const P& b, const P& c)
{
    const i128 ux = b[0] - a[0], uy = b[1] - a[1], uz = b[2] - a[2];
    const i128 vx = c[0] - a[0], vy = c[1] - a[1], vz = c[2] - a[2];
    const i128 n[3] = {uy * vz - uz * vy, uz * vx - ux * vz, ux * vy - uy * vx};
    auto mag = [](i128 x) { return x < 0 ? -x : x; };
    int k = 0;
    for (int i = 1; i < 3; ++i)
        if (mag(n[i]) > mag(n[k])) k = i;
    return {(k + 1) % 3, (k + 2) % 3};
}

bool on_segment_2d(const P& a, const P& b, const P& p, int u, int v)
{
    return std::min(a[u], b[u]) <= p[u] && p[u] <= std::max(a[u], b[u]) && std::min(a[v], b[v]) <= p[v] &&
           p[v] <= std::max(a[v], b[v]);
}

/// Closed segments (p, q) and (r, s) in the plane (u, v) intersect.
bool segments_intersect_2d(const P& p, const P& q, const P& r, const P& s, int u, int v)
{
    const int o1 = orient2d(p, q, r, u, v), o2 = orient2d(p, q, s, u, v);
    const int o3 = orient2d(r, s, p, u, v), o4 = orient2d(r, s, q, u, v);
    if (o1 != o2 && o3 != o4 && o1 * o2 <= 0 && o3 * o4 <= 0) {
        if (o1 != 0 || o2 != 0 || o3 != 0 || o4 != 0) return true;
    }
    // Collinear or touching cases.
    if (o1 == 0 && on_segment_2d(p, q, r, u, v)) return true;
    if (o2 == 0 && on_segment_2d(p, q, s, u, v)) return true;
    if (o3 == 0 && on_segment_2d(r, s, p, u, v)) return true;
    if (o4 == 0 && on_segment_2d(r, s, q, u, v)) return true;
    return false;
}

/// Point p inside or on the closed triangle (a, b, c) in the plane (u, v).
bool point_in_triangle_2d(const P& a, const P& b, const P& c, const P& p, int u, int v)
{
    const int o1 = orient2d(a, b, p, u, v), o2 = orient2d(b, c, p, u, v), o3 = orient2d(c, a, p, u, v);
    const bool has_neg = o1 < 0 || o2 < 0 || o3 < 0, has_pos = o1 > 0 || o2 > 0 || o3 > 0;
    return !(has_neg && has_pos);
}

bool degenerate(const P& a, const P& b, const P& c)
{
    const auto [u, v] = projection(a, b, c);
    // The dominant normal component is zero only when all are: collinear points.
    return orient2d(a, b, c, u, v) == 0 && orient2d(a, b, c, (u + 1) % 3, (v + 1) % 3) == 0 &&
           orient2d(a, b, c, (u + 2) % 3, (v + 2) % 3) == 0;
}

/// Closed segment (p, q) meets the closed, non-degenerate triangle (a, b, c).
bool segment_meets_triangle(const P& p, const P& q, const P& a, const P& b, const P& c)
{
    const int sp = orient3d(a, b, c, p), sq = orient3d(a, b, c, q);
    if (sp * sq > 0) return false; // both strictly on one side
    if (sp == 0 && sq == 0) {
        // In the triangle's plane: 2-D test.
        const auto [u, v] = projection(a, b, c);
        if (point_in_triangle_2d(a, b, c, p, u, v) || point_in_triangle_2d(a, b, c, q, u, v)) return true;
        return segments_intersect_2d(p, q, a, b, u, v) || segments_intersect_2d(p, q, b, c, u, v) ||
               segments_intersect_2d(p, q, c, a, u, v);
    }
    // The segment reaches the plane; it meets the triangle when the line pq
    // passes through it: the three volumes have no two opposite signs.
    const int o1 = orient3d(p, q, a, b), o2 = orient3d(p, q, b, c), o3 = orient3d(p, q, c, a);
    const bool has_neg = o1 < 0 || o2 < 0 || o3 < 0, has_pos = o1 > 0 || o2 > 0 || o3 > 0;
    return !(has_neg && has_pos);
}

/// Closed segments in space meet (used for degenerate triangles).
bool segments_meet_3d(const P& p, const P& q, const P& r, const P& s)
{
    if (orient3d(p, q, r, s) != 0) return false; // skew
    if (p == q && r == s) return p == r;
    // Coplanar: project on a plane where the four points keep their shape.
    for (int drop = 0; drop < 3; ++drop) {
        const int u = (drop + 1) % 3, v = (drop + 2) % 3;
        // A projection that squashes both segments to points or lines along the
        // dropped axis loses information; use one where either segment keeps length.
        if ((p[u] != q[u] || p[v] != q[v]) || (r[u] != s[u] || r[v] != s[v])) {
            if (!segments_intersect_2d(p, q, r, s, u, v)) return false;
        }
    }
    return true;
}

bool tri_tri(const std::array<P, 3>& A, const std::array<P, 3>& B)
{
    const bool da = degenerate(A[0], A[1], A[2]), db = degenerate(B[0], B[1], B[2]);
    auto edges_meet_triangle = [](const std::array<P, 3>& E, const std::array<P, 3>& T) {
        for (int i = 0; i < 3; ++i)
            if (segment_meets_triangle(E[i], E[(i + 1) % 3], T[0], T[1], T[2])) return true;
        return false;
    };
    if (!da && !db) return edges_meet_triangle(A, B) || edges_meet_triangle(B, A);
    if (da && db) {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (segments_meet_3d(A[i], A[(i + 1) % 3], B[j], B[(j + 1) % 3])) return true;
        return false;
    }
    // One degenerate (a segment, counted by its edges) against a proper triangle.
    return da ? edges_meet_triangle(A, B) : edges_meet_triangle(B, A);
}

} // namespace

bool triangles_intersect(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& a2,
                         const Eigen::Vector3d& b0, const Eigen::Vector3d& b1, const Eigen::Vector3d& b2)
{
    for (const auto* x : {&a0, &a1, &a2, &b0, &b1, &b2})
        if (!x->allFinite() || x->cwiseAbs().maxCoeff() > kMaxCoord)
            throw ParameterError("triangles_intersect: a coordinate is not finite or beyond 100 m");
    return tri_tri({snap(a0), snap(a1), snap(a2)}, {snap(b0), snap(b1), snap(b2)});
}

SelfIntersections self_intersections(const Positions& X, const Triangles& F)
{
    const int n = static_cast<int>(X.rows());
    if (!X.allFinite()) throw ParameterError("self-intersection test: a vertex position is not finite");
    if (n > 0 && X.cwiseAbs().maxCoeff() > kMaxCoord)
        throw ParameterError("self-intersection test: a vertex is " + format_value(X.cwiseAbs().maxCoeff()) +
                             " m from the origin (at most 100 m)");
    for (Eigen::Index t = 0; t < F.rows(); ++t)
        for (int k = 0; k < 3; ++k)
            if (F(t, k) < 0 || F(t, k) >= n)
                throw ParameterError("self-intersection test: triangle " + std::to_string(t) + " has vertex index " +
                                     std::to_string(F(t, k)) + " outside [0, " + std::to_string(n) + ")");
    std::vector<P> lattice(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) lattice[static_cast<std::size_t>(i)] = snap(X.row(i).transpose());
    std::vector<detail::Box> boxes(static_cast<std::size_t>(F.rows()));
    for (Eigen::Index t = 0; t < F.rows(); ++t)
        for (int k = 0; k < 3; ++k) {
            boxes[static_cast<std::size_t>(t)].add(Eigen::Vector3d(X.row(F(t, k)).transpose()));
        }
    SelfIntersections out;
    const detail::Bvh bvh(std::move(boxes));
    bvh.self_pairs([&](int a, int b) {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                if (F(a, i) == F(b, j)) return; // adjacent: shares a vertex
        ++out.candidates;
        const std::array<P, 3> A = {lattice[static_cast<std::size_t>(F(a, 0))], lattice[static_cast<std::size_t>(F(a, 1))],
                                    lattice[static_cast<std::size_t>(F(a, 2))]};
        const std::array<P, 3> B = {lattice[static_cast<std::size_t>(F(b, 0))], lattice[static_cast<std::size_t>(F(b, 1))],
                                    lattice[static_cast<std::size_t>(F(b, 2))]};
        if (tri_tri(A, B)) {
            ++out.pairs;
            if (out.sample.size() < 32) out.sample.emplace_back(std::min(a, b), std::max(a, b));
        }
    });
    return out;
}

} // namespace drape::cloth
