#include "engine/cloth/mesh.hpp"

#include "engine/core/error.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>
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

} // namespace drape::cloth
