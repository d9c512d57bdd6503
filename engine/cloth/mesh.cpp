#include "engine/cloth/mesh.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
#include <numbers>
#include <string>

namespace drape::cloth {

Eigen::VectorXd ClothMesh::vertex_areas() const
{
    Eigen::VectorXd a = Eigen::VectorXd::Zero(X.rows());
    for (int t = 0; t < F.rows(); ++t) {
        const Eigen::Vector3d p0 = X.row(F(t, 0)), p1 = X.row(F(t, 1)), p2 = X.row(F(t, 2));
        const double at = 0.5 * (p1 - p0).cross(p2 - p0).norm();
        for (int c = 0; c < 3; ++c) a(F(t, c)) += at / 3.0;
    }
    return a;
}

double ClothMesh::area() const { return vertex_areas().sum(); }

namespace {

/// Marks vertices on edges used by exactly one triangle.
std::vector<char> boundary_vertices(int nverts, const Triangles& F)
{
    std::map<std::pair<int, int>, int> count;
    for (int t = 0; t < F.rows(); ++t)
        for (int e = 0; e < 3; ++e) {
            int a = F(t, e), b = F(t, (e + 1) % 3);
            if (a > b) std::swap(a, b);
            ++count[{a, b}];
        }
    std::vector<char> bnd(static_cast<std::size_t>(nverts), 0);
    for (const auto& [edge, c] : count)
        if (c == 1) bnd[static_cast<std::size_t>(edge.first)] = bnd[static_cast<std::size_t>(edge.second)] = 1;
    return bnd;
}

/// Builds a grid mesh from a node mask: triangles for every cell with 3 or 4
/// nodes present (a 4-node cell is split along its (i,j)-(i+1,j+1) diagonal),
/// unused nodes dropped.
ClothMesh grid_mesh(int nu, int nv, double hu, double hv, const Eigen::Vector3d& origin, const std::vector<char>& keep)
{
    ClothMesh m;
    m.grid.nu = nu;
    m.grid.nv = nv;
    m.grid.hu = hu;
    m.grid.hv = hv;
    auto kept = [&](int i, int j) {
        return i >= 0 && j >= 0 && i < nu && j < nv && keep[static_cast<std::size_t>(i + nu * j)];
    };
    // First pass: which nodes are used by a triangle.
    std::vector<std::array<int, 6>> tris; // node (i,j) pairs
    for (int j = 0; j + 1 < nv; ++j)
        for (int i = 0; i + 1 < nu; ++i) {
            const bool a = kept(i, j), b = kept(i + 1, j), c = kept(i + 1, j + 1), d = kept(i, j + 1);
            const int n = a + b + c + d;
            if (n == 4) {
                tris.push_back({i, j, i + 1, j, i + 1, j + 1});
                tris.push_back({i, j, i + 1, j + 1, i, j + 1});
            } else if (n == 3) {
                if (!a) tris.push_back({i + 1, j, i + 1, j + 1, i, j + 1});
                else if (!b) tris.push_back({i, j, i + 1, j + 1, i, j + 1});
                else if (!c) tris.push_back({i, j, i + 1, j, i, j + 1});
                else tris.push_back({i, j, i + 1, j, i + 1, j + 1});
            }
        }
    m.grid.index.assign(static_cast<std::size_t>(nu * nv), -1);
    int nvtx = 0;
    for (const auto& t : tris)
        for (int c = 0; c < 3; ++c) {
            int& idx = m.grid.index[static_cast<std::size_t>(t[2 * c] + nu * t[2 * c + 1])];
            if (idx < 0) idx = nvtx++;
        }
    // Number vertices in grid order so neighbouring nodes stay close in memory.
    nvtx = 0;
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            int& idx = m.grid.index[static_cast<std::size_t>(i + nu * j)];
            if (idx >= 0) idx = nvtx++;
        }
    m.X.resize(nvtx, 3);
    m.uv.resize(nvtx, 2);
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) {
            const int idx = m.grid.at(i, j);
            if (idx < 0) continue;
            m.X.row(idx) = origin.transpose() + Eigen::RowVector3d(i * hu, j * hv, 0.0);
            m.uv.row(idx) = Eigen::RowVector2d(i * hu, j * hv);
        }
    m.F.resize(static_cast<int>(tris.size()), 3);
    for (std::size_t t = 0; t < tris.size(); ++t)
        for (int c = 0; c < 3; ++c) m.F(static_cast<int>(t), c) = m.grid.at(tris[t][2 * c], tris[t][2 * c + 1]);
    m.boundary = boundary_vertices(nvtx, m.F);
    m.on_grid_line.assign(static_cast<std::size_t>(nvtx), 1);
    return m;
}

} // namespace

ClothMesh make_disc(double diameter, int n, double z)
{
    if (!(diameter > 0) || !std::isfinite(diameter))
        throw ParameterError("make_disc: diameter = " + std::to_string(diameter) + " m must be positive");
    if (n < 5 || n > 2000) throw ParameterError("make_disc: grid = " + std::to_string(n) + " must be in [5, 2000]");
    const double R = diameter / 2;
    const double h = diameter / (n - 1);
    std::vector<char> keep(static_cast<std::size_t>(n * n), 0);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double x = -R + i * h, y = -R + j * h;
            keep[static_cast<std::size_t>(i + n * j)] = std::hypot(x, y) <= R * (1 + 1e-12);
        }
    ClothMesh m = grid_mesh(n, n, h, h, Eigen::Vector3d(-R, -R, z), keep);
    // Move the hem nodes radially onto the cut circle: the sheet then has the
    // specimen's true outline and area instead of a staircase that would bias
    // the drape coefficient by several points at coarse grids.
    for (int i = 0; i < m.vertex_count(); ++i) {
        if (!m.boundary[static_cast<std::size_t>(i)]) continue;
        const double r = std::hypot(m.X(i, 0), m.X(i, 1));
        if (r <= 0) continue;
        const double s = R / r;
        if (std::abs(s - 1) > 1e-12) {
            m.X(i, 0) *= s;
            m.X(i, 1) *= s;
            m.uv(i, 0) = m.X(i, 0) + R;
            m.uv(i, 1) = m.X(i, 1) + R;
            m.on_grid_line[static_cast<std::size_t>(i)] = 0;
        }
    }
    return m;
}

ClothMesh make_rectangle(double w, double h, int nu, int nv, const Eigen::Vector3d& origin)
{
    if (!(w > 0) || !(h > 0) || !std::isfinite(w) || !std::isfinite(h))
        throw ParameterError("make_rectangle: size " + std::to_string(w) + " x " + std::to_string(h) + " m must be positive");
    if (nu < 2 || nv < 2 || nu > 4000 || nv > 4000)
        throw ParameterError("make_rectangle: grid " + std::to_string(nu) + " x " + std::to_string(nv) + " must be in [2, 4000]");
    std::vector<char> keep(static_cast<std::size_t>(nu * nv), 1);
    return grid_mesh(nu, nv, w / (nu - 1), h / (nv - 1), origin, keep);
}

ClothMesh make_triangle_mesh(const Positions& X, const Triangles& F, const Eigen::Vector3d& warp)
{
    if (X.rows() < 3 || F.rows() < 1)
        throw ParameterError("make_triangle_mesh: mesh has " + std::to_string(X.rows()) + " vertices and " +
                             std::to_string(F.rows()) + " triangles");
    if (!X.allFinite()) throw ParameterError("make_triangle_mesh: vertex coordinates are not all finite");
    if (F.minCoeff() < 0 || F.maxCoeff() >= X.rows())
        throw ParameterError("make_triangle_mesh: a triangle index is outside [0, " + std::to_string(X.rows() - 1) + "]");
    ClothMesh m;
    m.X = X;
    m.F = F;
    // Material frame: best-fit plane of the rest shape, u = warp projected into it.
    const Eigen::RowVector3d c = X.colwise().mean();
    const Eigen::MatrixXd Y = X.rowwise() - c;
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Y, Eigen::ComputeThinV);
    Eigen::Vector3d nrm = svd.matrixV().col(2);
    Eigen::Vector3d u = warp - warp.dot(nrm) * nrm;
    if (u.norm() < 1e-9) u = svd.matrixV().col(0);
    u.normalize();
    const Eigen::Vector3d v = nrm.cross(u);
    m.uv.resize(X.rows(), 2);
    for (int i = 0; i < X.rows(); ++i) m.uv.row(i) = Eigen::RowVector2d(Y.row(i).dot(u.transpose()), Y.row(i).dot(v.transpose()));
    m.boundary = boundary_vertices(static_cast<int>(X.rows()), F);
    m.on_grid_line.assign(static_cast<std::size_t>(X.rows()), 0);
    return m;
}

ClothMesh make_ring_disc(double diameter, int n, const RingGrading& grading, double z)
{
    if (!(diameter > 0) || !std::isfinite(diameter))
        throw ParameterError("make_ring_disc: diameter = " + format_double(diameter) + " m must be positive");
    if (n < 5 || n > 2000) throw ParameterError("make_ring_disc: grid = " + std::to_string(n) + " must be in [5, 2000]");
    // At least 0.05 of the nominal spacing: a finer band multiplies the vertex
    // count past what a drape can hold (0.01 gives 2 million at grid 41).
    if (!(grading.factor >= 0.05) || grading.factor > 1)
        throw ParameterError("make_ring_disc: grading factor " + format_value(grading.factor) + " must be in [0.05, 1]");
    if (!(grading.taper >= 0) || !std::isfinite(grading.taper))
        throw ParameterError("make_ring_disc: grading taper " + format_value(grading.taper) + " m must be a non-negative length");
    if (!(grading.inner_radius >= 0) || !std::isfinite(grading.outer_radius) || grading.outer_radius < grading.inner_radius)
        throw ParameterError("make_ring_disc: grading band " + format_value(grading.inner_radius) + " .. " + format_value(grading.outer_radius) +
                             " m must run from a non-negative inner radius to an outer radius at least as large");
    const double R = diameter / 2, h0 = diameter / (n - 1);
    // Local spacing at radius r: h0, times `factor` inside the band, tapering
    // linearly back to h0 over `taper` on either side.
    auto spacing = [&](double r) {
        const double lo = grading.inner_radius, hi = grading.outer_radius, t = grading.taper;
        double b = 0;
        if (grading.factor < 1 && hi > lo) {
            if (r >= lo && r <= hi) b = 1;
            else if (t > 0 && r > lo - t && r < lo) b = (r - (lo - t)) / t;
            else if (t > 0 && r > hi && r < hi + t) b = ((hi + t) - r) / t;
        }
        return h0 * (1 - (1 - grading.factor) * b);
    };
    // Ring radii: each step the spacing at its midpoint; the last ring on the
    // hem - of the two rings either side of R the nearer one, all radii scaled
    // so that it lands on R (no sliver ring at the hem).
    std::vector<double> radii;
    for (double r = 0; r < R - 1e-12 * R;) {
        r += spacing(r + 0.5 * spacing(r));
        radii.push_back(r);
    }
    if (radii.size() > 1 && radii.back() - R > R - radii[radii.size() - 2]) radii.pop_back();
    const double scale = R / radii.back();
    for (double& r : radii) r *= scale;
    const int K = static_cast<int>(radii.size());
    std::vector<Eigen::Vector2d> P{Eigen::Vector2d::Zero()};
    std::vector<std::vector<int>> ring{{0}};
    // Each ring turned by the golden angle against the one inside it: no ring's
    // vertices line up with another's, so the mesh has no preferred directions
    // (fold crests find no lattice directions to settle on, as on a square
    // lattice; docs/decisions/0019-drapemeter-mesh.md).
    const double golden = std::numbers::pi * (3 - std::sqrt(5.0));
    for (int k = 1; k <= K; ++k) {
        const double r = radii[static_cast<std::size_t>(k - 1)];
        const int m = std::max(6, static_cast<int>(std::lround(2 * std::numbers::pi * r / spacing(r))));
        std::vector<int> ids;
        ids.reserve(static_cast<std::size_t>(m));
        for (int i = 0; i < m; ++i) {
            const double t = golden * k + 2 * std::numbers::pi * i / m;
            ids.push_back(static_cast<int>(P.size()));
            P.emplace_back(r * std::cos(t), r * std::sin(t));
        }
        ring.push_back(std::move(ids));
    }
    auto angle = [&](int v) { return std::atan2(P[static_cast<std::size_t>(v)].y(), P[static_cast<std::size_t>(v)].x()); };
    std::vector<Eigen::Vector3i> F;
    const auto& first = ring[1];
    for (std::size_t i = 0; i < first.size(); ++i) F.emplace_back(0, first[i], first[(i + 1) % first.size()]);
    // Zip each ring to the next by angle: advance on whichever ring's next
    // vertex comes first going round.
    for (int k = 2; k <= K; ++k) {
        const auto& a = ring[static_cast<std::size_t>(k - 1)];
        const auto& b = ring[static_cast<std::size_t>(k)];
        const int na = static_cast<int>(a.size()), nb = static_cast<int>(b.size());
        auto start = [&](const std::vector<int>& v) {
            int s = 0;
            for (int i = 1; i < static_cast<int>(v.size()); ++i)
                if (angle(v[static_cast<std::size_t>(i)]) < angle(v[static_cast<std::size_t>(s)])) s = i;
            return s;
        };
        const int sa = start(a), sb = start(b);
        auto unwrapped = [&](const std::vector<int>& v, int s, int i) {
            const int size = static_cast<int>(v.size());
            if (i == size) return 2 * std::numbers::pi;
            double t = angle(v[static_cast<std::size_t>((s + i) % size)]) - angle(v[static_cast<std::size_t>(s)]);
            while (t < 0) t += 2 * std::numbers::pi;
            return t;
        };
        // Both rings from their vertex of smallest angle (atan2's, past -pi),
        // angles going round measured from there.
        int i = 0, j = 0;
        while (i < na || j < nb) {
            const int ia = a[static_cast<std::size_t>((sa + i) % na)], ia1 = a[static_cast<std::size_t>((sa + i + 1) % na)];
            const int jb = b[static_cast<std::size_t>((sb + j) % nb)], jb1 = b[static_cast<std::size_t>((sb + j + 1) % nb)];
            const bool advance_inner = j >= nb || (i < na && unwrapped(a, sa, i + 1) < unwrapped(b, sb, j + 1));
            if (advance_inner) {
                F.emplace_back(ia, jb, ia1);
                ++i;
            } else {
                F.emplace_back(ia, jb, jb1);
                ++j;
            }
        }
    }
    Positions X(static_cast<Eigen::Index>(P.size()), 3);
    for (std::size_t v = 0; v < P.size(); ++v) X.row(static_cast<Eigen::Index>(v)) << P[v].x(), P[v].y(), z;
    Triangles T(static_cast<Eigen::Index>(F.size()), 3);
    for (std::size_t t = 0; t < F.size(); ++t) {
        Eigen::Vector3i f = F[t];
        const Eigen::Vector2d e1 = P[static_cast<std::size_t>(f[1])] - P[static_cast<std::size_t>(f[0])];
        const Eigen::Vector2d e2 = P[static_cast<std::size_t>(f[2])] - P[static_cast<std::size_t>(f[0])];
        // The zip writes its triangles counter-clockwise; a clockwise one means two
        // rings' vertex counts jumped so far that the sheet folded over itself
        // (grids 5-6 on a 360 mm sheet over a 115 mm disc, and on 500-760 mm sheets). Refused, not turned back over.
        if (!(e1.x() * e2.y() - e1.y() * e2.x() > 0))
            throw ParameterError("make_ring_disc: grid " + std::to_string(n) + " on a " + format_value(diameter * 1e3) +
                                 " mm disc with this grading folds the rings over each other; use a finer grid");
        T.row(static_cast<Eigen::Index>(t)) = f.transpose();
    }
    ClothMesh m = make_triangle_mesh(X, T);
    // Material coordinates as make_disc's: u along x (warp), v along y (weft),
    // from the corner (-R, -R) - whatever side the best-fit plane's normal took.
    for (int i = 0; i < m.vertex_count(); ++i) m.uv.row(i) << X(i, 0) + R, X(i, 1) + R;
    return m;
}

} // namespace drape::cloth
