#include "engine/cloth/model.hpp"

#include "engine/cloth/self_contact.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>

namespace drape::cloth {

namespace {

constexpr double kEulerPinned = 9.869604401089358; // pi^2: the Euler stress pi^2 B / l^2 of a strip with pinned ends

void add_common(ClothModel& m, const ClothMesh& mesh, double contact_depth)
{
    const int n = mesh.vertex_count();
    m.pinned.assign(static_cast<std::size_t>(n), 0);
    m.contact_stiffness.resize(n);
    const double g = m.gravity.norm();
    for (int i = 0; i < n; ++i) m.contact_stiffness(i) = m.mass(i) * std::max(g, 1.0) / contact_depth;
}

void add_spring(ClothModel& m, const ClothMesh& mesh, int a, int b, double k, double d, SpringKind kind)
{
    if (a < 0 || b < 0) return;
    const double rest = (mesh.X.row(a) - mesh.X.row(b)).norm();
    m.springs.push_back({a, b, rest, k, d, kind});
}

/// The compression limit of a spring standing for a strip of cloth of width w and
/// length L with bending rigidity B along it: the lower of the fabric's own limit,
/// the Euler stress pi^2 B / lb^2 per unit width (Param::BucklingLength lb), and the
/// Euler load of the strip, pi^2 B w / L^2, at which a strip longer than lb buckles
/// between its two nodes where the mesh cannot show it. So fc = pi^2 B w /
/// max(lb, L)^2: on meshes finer than lb the material law, the same on every mesh;
/// on coarser ones (a garment's 10-20 mm) the strip gives way at its own Euler load,
/// as the first buckling model did everywhere. With the material law alone a coarse
/// skirt could not fold below lb: the denim skirt locked (4 folds, hem radius 373 mm
/// instead of 202 mm) and the silk skirt's folds crossed (288 self-intersections).
double compression_limit(double B, double w, double L, double lb)
{
    const double l = std::max(lb, L);
    return kEulerPinned * B * w / (l * l);
}

/// Weights of a stencil over four material points that annihilate every affine
/// function of (u, v) (the kernel of the 3x4 matrix [1; u; v]), scaled so that the
/// stencil applied to the quadratic q(u - u0, v - v0) gives 1: q = du^2 / 2 makes it
/// the second derivative along u, du dv the mixed derivative. Flat sheets, however
/// mapped affinely, then have zero bending energy. false: the points are degenerate
/// (collinear) or the stencil cannot see q.
template <class Q>
bool kernel_weights(const ClothMesh& mesh, const int (&ids)[4], Q q, double (&w)[4])
{
    Eigen::Matrix<double, 3, 4> C;
    for (int i = 0; i < 4; ++i) C.col(i) << 1.0, mesh.uv(ids[i], 0), mesh.uv(ids[i], 1);
    Eigen::FullPivLU<Eigen::Matrix<double, 3, 4>> lu(C);
    const Eigen::Matrix<double, 4, Eigen::Dynamic> ker = lu.kernel();
    if (ker.cols() != 1) return false;
    double norm = 0;
    for (int i = 0; i < 4; ++i)
        norm += ker(i, 0) * q(mesh.uv(ids[i], 0) - mesh.uv(ids[0], 0), mesh.uv(ids[i], 1) - mesh.uv(ids[0], 1));
    if (!(std::abs(norm) > 1e-300)) return false;
    for (int i = 0; i < 4; ++i) w[i] = ker(i, 0) / norm;
    return true;
}

/// Appends the bending stencil over the n nodes `ids` with weights `w`.
void add_stencil(ClothModel& m, int n, const int* ids, const double* w, double k, double d, double quartic = 0)
{
    BendStencil st;
    st.n = n;
    for (int q = 0; q < n; ++q) {
        st.v[q] = ids[q];
        st.w[q] = w[q];
    }
    st.k = k;
    st.d = d;
    st.quartic = quartic;
    m.bends.push_back(st);
}

bool all_on_grid(const ClothMesh& mesh, std::initializer_list<int> ids)
{
    for (int i : ids)
        if (!mesh.on_grid_line[static_cast<std::size_t>(i)]) return false;
    return true;
}

/// Material area of the polygon through the given vertices (in order) [m^2].
double material_area(const ClothMesh& mesh, std::initializer_list<int> ids)
{
    double a2 = 0;
    for (auto it = ids.begin(); it != ids.end(); ++it) {
        const int x = *it, y = std::next(it) == ids.end() ? *ids.begin() : *std::next(it);
        a2 += mesh.uv(x, 0) * mesh.uv(y, 1) - mesh.uv(x, 1) * mesh.uv(y, 0);
    }
    return 0.5 * std::abs(a2);
}

/// Weights over the existing nodes of the 3x3 block of grid nodes around (i, j)
/// that reproduce one second derivative of every quadratic f(u, v) exactly:
/// sum_k w_k f(u_k, v_k) = a f_uu + b f_uv + c f_vv with (a, b, c) = `want`; the
/// smallest such weights (minimum norm) when more than six nodes exist. It is
/// zero for every affine f, so a flat sheet, however mapped, does not bend.
/// Used where make_disc moved a node off its grid node onto the hem: there three
/// nodes of a grid line are no longer on a line and a cell is no longer a
/// rectangle, and the grid's own stencils would see the other derivatives too.
/// false: the block's nodes cannot tell the quadratics apart.
int hem_weights(const ClothMesh& mesh, int i, int j, const double (&want)[3], int (&ids)[BendStencil::kMax], double (&w)[BendStencil::kMax])
{
    const auto& g = mesh.grid;
    int n = 0;
    for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di)
            if (const int x = g.at(i + di, j + dj); x >= 0) ids[n++] = x;
    if (n < 6) return 0;
    const int c = g.at(i, j);
    Eigen::Matrix<double, 6, Eigen::Dynamic> P(6, n);
    for (int q = 0; q < n; ++q) {
        const double du = (mesh.uv(ids[q], 0) - mesh.uv(c, 0)) / g.hu, dv = (mesh.uv(ids[q], 1) - mesh.uv(c, 1)) / g.hv;
        P.col(q) << 1.0, du, dv, du * du, du * dv, dv * dv; // monomials in cell units
    }
    // The wanted derivative of each monomial in cell units: f_uu of (u/hu)^2 is
    // 2/hu^2, f_uv of (u/hu)(v/hv) is 1/(hu hv); the weights come out in 1/m^2.
    Eigen::Matrix<double, 6, 1> t;
    t << 0, 0, 0, 2 * want[0] / (g.hu * g.hu), want[1] / (g.hu * g.hv), 2 * want[2] / (g.hv * g.hv);
    const Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(P);
    if (cod.rank() < 6) return 0;
    const Eigen::VectorXd x = cod.solve(t);
    for (int q = 0; q < n; ++q) w[q] = x(q);
    return n;
}

bool hem_stencil(ClothModel& m, const ClothMesh& mesh, int i, int j, const double (&want)[3], double k, double d, double quartic)
{
    int ids[BendStencil::kMax];
    double w[BendStencil::kMax];
    const int n = hem_weights(mesh, i, j, want, ids, w);
    if (n == 0) return false;
    add_stencil(m, n, ids, w, k, d, quartic);
    return true;
}

/// The second derivative of the positions along the material direction (a, b)
/// (a unit vector in (u, v)) at grid node (i, j): a^2 x_uu + 2 a b x_uv + b^2 x_vv
/// by central differences where the nodes it needs are on their grid nodes, else
/// hem_weights' least squares over the 3x3 block. Returns the number of weights,
/// 0 where neither can be had.
int node_curvature_weights(const ClothMesh& mesh, int i, int j, double a, double b, int (&ids)[BendStencil::kMax],
                           double (&w)[BendStencil::kMax])
{
    const auto& g = mesh.grid;
    const double wu = a * a / (g.hu * g.hu), wv = b * b / (g.hv * g.hv), wx = 2 * a * b / (4 * g.hu * g.hv);
    int n = 0;
    bool ok = true;
    auto put = [&](int di, int dj, double weight) { // each offset once: nine distinct nodes
        if (weight == 0) return;
        const int x = g.at(i + di, j + dj);
        if (x < 0 || !mesh.on_grid_line[static_cast<std::size_t>(x)]) {
            ok = false;
            return;
        }
        ids[n] = x;
        w[n++] = weight;
    };
    put(0, 0, -2 * wu - 2 * wv);
    put(-1, 0, wu);
    put(1, 0, wu);
    put(0, -1, wv);
    put(0, 1, wv);
    put(1, 1, wx);
    put(-1, -1, wx);
    put(1, -1, -wx);
    put(-1, 1, -wx);
    if (ok) return n;
    // A full block with nodes moved onto the hem: least squares over its nine nodes.
    // With fewer (six to eight: the block reaches past the cut circle) the quadratic
    // through them extrapolates; on an isometric bend of 16 mm radius such hem ends read
    // up to 2 % strain where the chord reads none: none then.
    const double want[3] = {a * a, 2 * a * b, b * b};
    return hem_weights(mesh, i, j, want, ids, w) == 9 ? 9 : 0;
}

/// SpringArc for every spring of the grid model `m` of `mesh` whose kind is in
/// `kinds` (ModelOptions::arc_membrane).
void add_spring_arcs(ClothModel& m, const ClothMesh& mesh, std::initializer_list<SpringKind> kinds)
{
    const auto& g = mesh.grid;
    std::vector<std::array<int, 2>> cell(static_cast<std::size_t>(mesh.vertex_count()), {-1, -1});
    for (int j = 0; j < g.nv; ++j)
        for (int i = 0; i < g.nu; ++i)
            if (const int x = g.at(i, j); x >= 0) cell[static_cast<std::size_t>(x)] = {i, j};
    for (auto& sp : m.springs) {
        if (std::find(kinds.begin(), kinds.end(), sp.kind) == kinds.end()) continue;
        Eigen::Vector2d d = (mesh.uv.row(sp.j) - mesh.uv.row(sp.i)).transpose();
        if (!(d.norm() > 0)) continue;
        d.normalize();
        const int ends[2] = {sp.i, sp.j};
        int ids[2][BendStencil::kMax], count[2] = {0, 0};
        double w[2][BendStencil::kMax];
        for (int e = 0; e < 2; ++e) {
            const auto [ci, cj] = cell[static_cast<std::size_t>(ends[e])];
            if (ci >= 0) count[e] = node_curvature_weights(mesh, ci, cj, d.x(), d.y(), ids[e], w[e]);
        }
        const int have = (count[0] > 0) + (count[1] > 0);
        if (have == 0) continue;
        SpringArc arc;
        arc.slot(sp.i);
        arc.slot(sp.j);
        const double c = sp.rest * sp.rest * sp.rest / 24;
        for (int e = 0; e < 2; ++e) {
            arc.c[e] = count[e] > 0 ? c / have : 0.0;
            for (int a = 0; a < count[e]; ++a) arc.w[e][arc.slot(ids[e][a])] = w[e][a];
        }
        sp.arc = static_cast<int>(m.arcs.size());
        m.arcs.push_back(arc);
    }
}

/// Grid-line stencil through (a, b, c) with divided-difference weights of their
/// material spacings, standing for the material area `area_b` (the centre's, with
/// the area of the hem node that ends the line lumped onto its inner neighbour).
/// Near the hem, where make_disc moved a node off its grid node onto the cut circle,
/// the stencil is hem_stencil's. Skipping those stencils, as the first version did,
/// left a ring about two cells wide along the hem with no bending stiffness,
/// narrower on finer grids: the denim starter on 8 folds drifted from D 75.5 % at
/// grid 41 to 77.7 % at grid 101.
/// `correct`: with the stencil's fourth-order correction (BendStencil::quartic).
void add_line_stencil(ClothModel& m, const ClothMesh& mesh, int a, int b, int c, double B, double cb, double area_b, int axis, int i,
                      int j, bool correct)
{
    if (a < 0 || b < 0 || c < 0) return;
    if (!all_on_grid(mesh, {a, b, c})) {
        const double want[3] = {axis == 0 ? 1.0 : 0.0, 0.0, axis == 1 ? 1.0 : 0.0};
        const double h = axis == 0 ? mesh.grid.hu : mesh.grid.hv;
        hem_stencil(m, mesh, i, j, want, B * area_b, cb * area_b, correct ? h * h / 3 : 0.0);
        return;
    }
    const double sa = mesh.uv(a, axis), sb = mesh.uv(b, axis), sc = mesh.uv(c, axis);
    const int ids[3] = {a, b, c};
    const double wa = 2.0 / ((sb - sa) * (sc - sa)), wc = 2.0 / ((sc - sb) * (sc - sa));
    const double w[3] = {wa, -(wa + wc), wc};
    // Nodes on grid lines are evenly spaced (moved hem nodes take hem_stencil above):
    // the three-point difference reads kappa (1 - h^2 kappa^2 / 12) on a bend.
    const double h = 0.5 * (sc - sa);
    add_stencil(m, 3, ids, w, B * area_b, cb * area_b, correct ? h * h / 3 : 0.0);
}

/// Twist stencil on a grid cell: the mixed derivative x_uv = (x11 - x10 - x01 + x00)/(hu hv),
/// energy B_t x_uv^2 hu hv (the 2 B_t kappa_uv^2 / 2 term of a plate with no Poisson
/// coupling). Without it a fold running diagonally to the grid would cost half the
/// bending energy of one along a grid line. B_t = sqrt(B_u B_v), the usual closure for
/// orthotropic fabrics.
/// A cell with a node moved onto the hem: hem_stencil's mixed derivative around
/// the cell's corner nearest the specimen's centre (its 3x3 block holds the most
/// nodes; the block of an outer corner may hold only five), else the kernel
/// weights over the cell's four nodes; standing for the cell's material area.
void add_twist_stencil(ClothModel& m, const ClothMesh& mesh, int a, int b, int c, int d, double Bt, double cb, double hu, double hv, int i,
                       int j, const Eigen::RowVector2d& centre, bool correct)
{
    const double quartic = correct ? 2 * hu * hv / 3 : 0.0;
    if (a < 0 || b < 0 || c < 0 || d < 0) return;
    if (!all_on_grid(mesh, {a, b, c, d})) {
        const double A = material_area(mesh, {a, b, d, c});
        const int corner[4][3] = {{a, i, j}, {b, i + 1, j}, {c, i, j + 1}, {d, i + 1, j + 1}};
        int best = 0;
        for (int q = 1; q < 4; ++q)
            if ((mesh.uv.row(corner[q][0]) - centre).squaredNorm() < (mesh.uv.row(corner[best][0]) - centre).squaredNorm()) best = q;
        if (hem_stencil(m, mesh, corner[best][1], corner[best][2], {0.0, 1.0, 0.0}, 2 * Bt * A, 2 * cb * A, quartic)) return;
        const int ids[4] = {a, b, c, d};
        double w[4];
        if (kernel_weights(mesh, ids, [](double du, double dv) { return du * dv; }, w))
            add_stencil(m, 4, ids, w, 2 * Bt * A, 2 * cb * A, quartic);
        return;
    }
    const int ids[4] = {a, b, c, d};
    const double w[4] = {1 / (hu * hv), -1 / (hu * hv), -1 / (hu * hv), 1 / (hu * hv)};
    add_stencil(m, 4, ids, w, 2 * Bt * hu * hv, 2 * cb * hu * hv, quartic);
}

/// Bending on a general triangle mesh: per triangle, the second derivatives
/// x_uu, x_uv, x_vv (material coordinates) of the quadratic through the
/// triangle's three vertices and the three across its edges (at the hem, a
/// seam of three or more panels, or where those fix a quadratic poorly: least
/// squares over up to nine nearby vertices, the best-conditioned set), as three
/// stencils: energy A (Bu |x_uu|^2 + 2 Bt |x_uv|^2 + Bv |x_vv|^2) / 2 with
/// Bt = sqrt(Bu Bv), the orthotropic plate the grid model discretises. Exact
/// for every quadratic surface, so a bend costs the same whatever its direction
/// and whatever the triangles' shapes. (The hinge stencil used until 2026-11-30
/// - the second difference across each edge, a third of the hinge's area -
/// gave 0.45 B on a disc of concentric rings and 0.34..0.95 B by direction on
/// a square lattice split into triangles, measured by rolling the disc
/// isometrically onto a cylinder at each direction: docs/decisions/0014-triangle-model-plate-and-fibres.md.)
void add_triangle_curvature_stencils(ClothModel& m, const ClothMesh& mesh, const std::map<std::pair<int, int>, std::vector<int>>& edge_tris,
                                     double Bu, double Bv, double cb)
{
    const int nt = static_cast<int>(mesh.F.rows());
    std::vector<std::vector<int>> vertex_tris(static_cast<std::size_t>(mesh.vertex_count()));
    for (int t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k) vertex_tris[static_cast<std::size_t>(mesh.F(t, k))].push_back(t);
    const double Bt = std::sqrt(Bu * Bv);
    for (int t = 0; t < nt; ++t) {
        const int tv[3] = {mesh.F(t, 0), mesh.F(t, 1), mesh.F(t, 2)};
        const double A = material_area(mesh, {tv[0], tv[1], tv[2]});
        if (!(A > 0)) continue;
        const Eigen::Vector2d centre = (mesh.uv.row(tv[0]) + mesh.uv.row(tv[1]) + mesh.uv.row(tv[2])).transpose() / 3.0;
        std::vector<int> pts(tv, tv + 3);
        auto add_point = [&](int v) {
            if (std::find(pts.begin(), pts.end(), v) == pts.end()) pts.push_back(v);
        };
        // Across each manifold edge (an edge of three or more triangles - a T-seam
        // of an imported garment - joins other panels: not part of this sheet's surface).
        for (int e = 0; e < 3; ++e) {
            const int a = std::min(tv[e], tv[(e + 1) % 3]), b = std::max(tv[e], tv[(e + 1) % 3]);
            const auto& across = edge_tris.at({a, b});
            if (across.size() != 2) continue;
            for (int u : across)
                if (u != t)
                    for (int k = 0; k < 3; ++k) add_point(mesh.F(u, k));
        }
        // At the hem (and a seam): the nearest vertices of the triangles around
        // its corners, one at a time while the points do not fix a quadratic well
        // (on a regular lattice the first ones may lie on two lines, a conic), up
        // to BendStencil::kMax; the best-conditioned set is kept.
        std::vector<int> more;
        for (int v : tv)
            for (int u : vertex_tris[static_cast<std::size_t>(v)])
                for (int k = 0; k < 3; ++k)
                    if (std::find(pts.begin(), pts.end(), mesh.F(u, k)) == pts.end() && std::find(more.begin(), more.end(), mesh.F(u, k)) == more.end())
                        more.push_back(mesh.F(u, k));
        std::sort(more.begin(), more.end(), [&](int x, int y) {
            return (mesh.uv.row(x).transpose() - centre).squaredNorm() < (mesh.uv.row(y).transpose() - centre).squaredNorm();
        });
        // z = c0 + c1 u + c2 v + a u^2 / 2 + b u v + c v^2 / 2 (u, v from the centre,
        // in units of L for conditioning); a, b, c are rows of the pseudo-inverse.
        const double L = std::sqrt(A);
        auto design = [&] {
            Eigen::MatrixXd P(static_cast<Eigen::Index>(pts.size()), 6);
            for (Eigen::Index i = 0; i < P.rows(); ++i) {
                const double u = (mesh.uv(pts[static_cast<std::size_t>(i)], 0) - centre.x()) / L;
                const double v = (mesh.uv(pts[static_cast<std::size_t>(i)], 1) - centre.y()) / L;
                P.row(i) << 1.0, u, v, 0.5 * u * u, u * v, 0.5 * v * v;
            }
            return P;
        };
        // Conditioning: smallest over largest singular value of the design (u, v in
        // units of sqrt(A)): 0.036..0.25, median 0.15, over the 4,914 triangles of the
        // split square lattice and the ring disc at grid 41 (measured 2026-11-30).
        auto conditioning = [](const Eigen::JacobiSVD<Eigen::MatrixXd>& s) {
            return s.singularValues().size() == 6 ? s.singularValues()(5) / s.singularValues()(0) : 0.0;
        };
        constexpr double kGood = 0.02, kUsable = 1e-3;
        Eigen::JacobiSVD<Eigen::MatrixXd> svd, best;
        std::vector<int> best_pts;
        double best_cond = 0;
        std::size_t next = 0;
        if (pts.size() > static_cast<std::size_t>(BendStencil::kMax)) continue; // cannot happen with manifold edges (3 + 3)
        while (true) {
            if (pts.size() >= 6) {
                svd.compute(design(), Eigen::ComputeThinU | Eigen::ComputeThinV);
                if (const double q = conditioning(svd); q > best_cond) {
                    best_cond = q;
                    best = svd;
                    best_pts = pts;
                }
                if (best_cond >= kGood) break;
            }
            if (next >= more.size() || static_cast<int>(pts.size()) >= BendStencil::kMax) break;
            pts.push_back(more[next++]);
        }
        if (best_cond < kUsable) continue; // the points do not fix a quadratic
        pts = best_pts;
        svd = best;
        const int np = static_cast<int>(pts.size());
        const auto& s = svd.singularValues();
        const Eigen::MatrixXd pinv = svd.matrixV() * s.cwiseInverse().asDiagonal() * svd.matrixU().transpose(); // 6 x np
        const double stiffness[3] = {Bu * A, 2 * Bt * A, Bv * A}, damping[3] = {cb * A, 2 * cb * A, cb * A};
        for (int comp = 0; comp < 3; ++comp) {
            double w[BendStencil::kMax];
            for (int i = 0; i < np; ++i) w[i] = pinv(3 + comp, i) / (L * L);
            add_stencil(m, np, pts.data(), w, stiffness[comp], damping[comp]);
        }
    }
}

/// The membrane of a general triangle mesh: per triangle, the continuum of the
/// grid's spring net (warp and weft springs, both diagonals), so that a preset
/// stretches, shears and buckles the same on a garment's mesh as on the
/// drapemeter's grid. Four fibre families at 0, 90, +45 and -45 degrees to the
/// warp in the triangle's rest plane (the mesh's own shape, so a panel imported
/// curved rests in it), each with the energy density of its grid springs:
/// warp max(Eu - G, Eu / 2) eps^2 / 2 (the diagonals carry G of Eu, as on the
/// grid), weft likewise, each diagonal 2 G eps^2 / 2 (so that a shear gamma
/// costs G gamma^2 / 2), eps the fibre's stretch |F e| - 1 under the triangle's
/// deformation gradient F. With a buckling length lb the compressive stress of a
/// family saturates at the Euler stress pi^2 B / max(lb, L)^2 of a strip of the
/// triangle's size L = sqrt(2 A) (sqrt(4 A) along the diagonals, bending
/// sqrt(Bu Bv)), the grid's compression_limit with its cell. Exact for affine
/// deformations on any triangulation, whatever the directions of its edges. As on
/// the grid, the diagonals couple warp and weft: Eu is the warp modulus with the
/// weft held (uniaxial, free weft: Eu - G^2 / Ev), and with G > Eu / 2 the warp's is
/// Eu / 2 + G. (Until
/// 2026-12-01: one isotropic spring per edge with E = (Eu + Ev) / 2, no shear
/// parameter, shear stiffness about 3E / 8 - for the cotton starter about 1,200
/// N/m against its 90.)
void add_triangle_membrane(ClothModel& m, const ClothMesh& mesh, const FabricParams& p)
{
    const double Eu = p[Param::StretchWarp], Ev = p[Param::StretchWeft], G = p[Param::Shear];
    const double Bu = p[Param::BendWarp], Bv = p[Param::BendWeft];
    const double cs = p[Param::DampStretch], csh = p[Param::DampShear];
    const double lb = p[Param::BucklingLength];
    const double r = std::sqrt(0.5);
    struct Family {
        Eigen::Vector2d dir;
        double E, c, B, length_scale; // modulus [N/m], damping [N*s/m], bending [N*m], strip length / sqrt(2 A)
    };
    const Family families[4] = {{{1, 0}, std::max(Eu - G, 0.5 * Eu), cs, Bu, 1.0},
                                {{0, 1}, std::max(Ev - G, 0.5 * Ev), cs, Bv, 1.0},
                                {{r, r}, 2 * G, 2 * csh, std::sqrt(Bu * Bv), std::sqrt(2.0)},
                                {{r, -r}, 2 * G, 2 * csh, std::sqrt(Bu * Bv), std::sqrt(2.0)}};
    // The rest shape is the mesh's own (X), flat or not: a garment panel imported in
    // its 3D shape is stress-free there, as the edge springs were. The warp is the
    // direction in space along which u grows (least squares over the vertices: exact
    // for make_triangle_mesh's projection), projected into each triangle's plane;
    // the weft is at right angles to it in that plane.
    Eigen::Vector3d warp3 = Eigen::Vector3d::UnitX();
    {
        Eigen::MatrixXd P(mesh.vertex_count(), 4);
        P.leftCols<3>() = mesh.X;
        P.col(3).setOnes();
        const Eigen::Vector4d c = P.colPivHouseholderQr().solve(mesh.uv.col(0));
        if (c.head<3>().allFinite() && c.head<3>().norm() > 0) warp3 = c.head<3>().normalized();
    }
    m.fibers.reserve(4 * static_cast<std::size_t>(mesh.F.rows()));
    for (int t = 0; t < mesh.F.rows(); ++t) {
        const int v0 = mesh.F(t, 0), v1 = mesh.F(t, 1), v2 = mesh.F(t, 2);
        const Eigen::Vector3d e1 = (mesh.X.row(v1) - mesh.X.row(v0)).transpose(), e2 = (mesh.X.row(v2) - mesh.X.row(v0)).transpose();
        const Eigen::Vector3d nrm = e1.cross(e2);
        if (!(nrm.norm() > 0)) continue; // a sliver with no area carries no membrane
        const Eigen::Vector3d n = nrm.normalized();
        Eigen::Vector3d a = warp3 - warp3.dot(n) * n;
        if (a.norm() < 0.1) a = e1; // the triangle stands almost across the warp: any in-plane axis
        a.normalize();
        const Eigen::Vector3d b = n.cross(a);
        Eigen::Matrix2d Dm; // the rest edges in the triangle's (warp, weft) frame
        Dm << a.dot(e1), a.dot(e2), b.dot(e1), b.dot(e2);
        const double A = 0.5 * std::abs(Dm.determinant());
        if (!(A > 0)) continue;
        const Eigen::Matrix2d Dinv = Dm.inverse(); // rows: gradients of the shape functions of v1, v2
        const double h = std::sqrt(2 * A);
        for (const Family& fam : families) {
            if (!(fam.E > 0)) continue;
            const double g1 = Dinv.row(0).dot(fam.dir), g2 = Dinv.row(1).dot(fam.dir);
            MembraneFiber fb;
            fb.v = {v0, v1, v2};
            fb.w = {-h * (g1 + g2), h * g1, h * g2};
            fb.rest = h;
            fb.k = fam.E * A / (h * h);
            fb.d = fam.c * A / (h * h);
            if (lb > 0) fb.fc = compression_limit(fam.B, A / h, fam.length_scale * h, lb);
            fb.slack = p[Param::CompressionSlack] * h;
            m.fibers.push_back(fb);
        }
    }
}

} // namespace

int SpringArc::slot(int x)
{
    for (int k = 0; k < n; ++k)
        if (v[k] == x) return k;
    // Each end's weights include the end itself: at most 2 + 2 (BendStencil::kMax - 1) nodes.
    if (n == kMax) throw std::logic_error("SpringArc: more than " + std::to_string(kMax) + " nodes");
    v[n] = x;
    return n++;
}

ClothModel make_model(const ClothMesh& mesh, const FabricParams& p, const ModelOptions& opt)
{
    p.validate();
    if (!(opt.contact_depth > 0)) throw ParameterError("ModelOptions: contact_depth must be positive");
    if (mesh.grid.valid() && opt.bending != BendingModel::Quadratic)
        throw ParameterError("make_model: flexion springs are grid constants; use GridSprings (a seed-19 preset) for them");
    ClothModel m;
    m.mass = p[Param::AreaDensity] * mesh.vertex_areas();
    m.air_damping = p[Param::DampAir];
    m.contact_offset = 0.5 * p[Param::Thickness];
    m.friction = p[Param::Friction];
    m.bend_stiffening = p[Param::BendStiffeningRadius] * p[Param::BendStiffeningRadius];
    m.bend_softening = p[Param::BendSofteningRadius] * p[Param::BendSofteningRadius];
    m.bend_peak = p[Param::BendPeakRadius] * p[Param::BendPeakRadius];
    add_common(m, mesh, opt.contact_depth);
    m.edge_contact = opt.edge_contact;
    m.self_contact_distance = opt.self_collision ? std::max(p[Param::Thickness], kMinSelfContactDistance) : 0.0;
    const double Eu = p[Param::StretchWarp], Ev = p[Param::StretchWeft], G = p[Param::Shear];
    const double Bu = p[Param::BendWarp], Bv = p[Param::BendWeft];
    const double cs = p[Param::DampStretch], csh = p[Param::DampShear], cb = p[Param::DampBend];
    const double lb = p[Param::BucklingLength];
    const bool quadratic = opt.bending != BendingModel::Flexion;
    if (mesh.grid.valid()) {
        const auto& g = mesh.grid;
        const double hu = g.hu, hv = g.hv;
        const double ku = std::max(Eu - G * hu * hu / (hv * hv), 0.5 * Eu) * hv / hu;
        const double kv = std::max(Ev - G * hv * hv / (hu * hu), 0.5 * Ev) * hu / hv;
        const double ksh = (hu * hu + hv * hv) / (2 * hu * hv);
        const Eigen::RowVector2d uv_centre = mesh.uv.colwise().mean();
        Eigen::VectorXd material_areas = Eigen::VectorXd::Zero(mesh.vertex_count());
        for (int t = 0; t < mesh.F.rows(); ++t) {
            const double at = material_area(mesh, {mesh.F(t, 0), mesh.F(t, 1), mesh.F(t, 2)});
            for (int c = 0; c < 3; ++c) material_areas(mesh.F(t, c)) += at / 3.0;
        }
        // The area each line stencil stands for: its centre's, plus that of a line's
        // end node (on the hem, no stencil along that line is centred there) lumped
        // onto its inner neighbour, so the stencils cover the whole specimen.
        Eigen::VectorXd line_area[2] = {material_areas, material_areas};
        for (int j = 0; j < g.nv; ++j)
            for (int i = 0; i < g.nu; ++i) {
                const int a = g.at(i, j);
                if (a < 0) continue;
                const int nb[2][2] = {{g.at(i - 1, j), g.at(i + 1, j)}, {g.at(i, j - 1), g.at(i, j + 1)}};
                for (int axis : {0, 1}) {
                    const int lo = nb[axis][0], hi = nb[axis][1];
                    if ((lo < 0) == (hi < 0)) continue; // inside the line, or alone on it
                    line_area[axis](lo >= 0 ? lo : hi) += material_areas(a);
                    line_area[axis](a) = 0;
                }
            }
        for (int j = 0; j < g.nv; ++j)
            for (int i = 0; i < g.nu; ++i) {
                const int a = g.at(i, j);
                if (a < 0) continue;
                add_spring(m, mesh, a, g.at(i + 1, j), ku, cs * hv / hu, SpringKind::StretchU);
                add_spring(m, mesh, a, g.at(i, j + 1), kv, cs * hu / hv, SpringKind::StretchV);
                add_spring(m, mesh, a, g.at(i + 1, j + 1), G * ksh, csh * ksh, SpringKind::Shear);
                if (g.at(i + 1, j) >= 0) add_spring(m, mesh, g.at(i + 1, j), g.at(i, j + 1), G * ksh, csh * ksh, SpringKind::Shear);
                if (quadratic) {
                    const bool corr = opt.bending_correction;
                    add_line_stencil(m, mesh, g.at(i - 1, j), a, g.at(i + 1, j), Bu, cb, line_area[0](a), 0, i, j, corr);
                    add_line_stencil(m, mesh, g.at(i, j - 1), a, g.at(i, j + 1), Bv, cb, line_area[1](a), 1, i, j, corr);
                    add_twist_stencil(m, mesh, a, g.at(i + 1, j), g.at(i, j + 1), g.at(i + 1, j + 1), std::sqrt(Bu * Bv), cb, hu, hv, i, j, uv_centre,
                                      corr);
                }
            }
        m.description = "grid mass-spring model (stretch, shear, quadratic bending) from continuum parameters";
        // Every family measures arcs: with the warp and weft springs alone the
        // diagonals across a fold still read its crest as compression
        // (docs/decisions/0019-drapemeter-mesh.md).
        if (opt.arc_membrane) add_spring_arcs(m, mesh, {SpringKind::StretchU, SpringKind::StretchV, SpringKind::Shear});
        if (lb > 0) {
            // The compression limit (Spring::fc, Param::BucklingLength) of the strip each
            // spring stands for: width hv (hu) and length hu (hv) for the warp (weft)
            // springs; the shear diagonals width hu hv / L and length L = sqrt(hu^2 +
            // hv^2), bending with the twist closure sqrt(Bu Bv).
            const double L = std::sqrt(hu * hu + hv * hv);
            for (auto& sp : m.springs) {
                if (sp.kind == SpringKind::StretchU) sp.fc = compression_limit(Bu, hv, hu, lb);
                else if (sp.kind == SpringKind::StretchV) sp.fc = compression_limit(Bv, hu, hv, lb);
                else if (sp.kind == SpringKind::Shear) sp.fc = compression_limit(std::sqrt(Bu * Bv), hu * hv / L, L, lb);
            }
        }
        if (const double slack = p[Param::CompressionSlack]; slack > 0)
            for (auto& sp : m.springs)
                if (sp.kind == SpringKind::StretchU || sp.kind == SpringKind::StretchV || sp.kind == SpringKind::Shear) sp.slack = slack * sp.rest;
        return m;
    }
    // General triangle mesh.
    std::map<std::pair<int, int>, std::vector<int>> edge_tris;
    for (int t = 0; t < mesh.F.rows(); ++t)
        for (int e = 0; e < 3; ++e) {
            int a = mesh.F(t, e), b = mesh.F(t, (e + 1) % 3);
            if (a > b) std::swap(a, b);
            edge_tris[{a, b}].push_back(t);
        }
    for (const auto& [edge, tris] : edge_tris)
        if ((mesh.uv.row(edge.first) - mesh.uv.row(edge.second)).squaredNorm() <= 0)
            throw ParameterError("make_model: zero-length edge between vertices " + std::to_string(edge.first) + " and " +
                                 std::to_string(edge.second));
    add_triangle_membrane(m, mesh, p);
    if (quadratic) add_triangle_curvature_stencils(m, mesh, edge_tris, Bu, Bv, cb);
    m.description = "triangle model (orthotropic fibre-net membrane, per-triangle curvature bending) from continuum parameters";
    return m;
}

void GridSprings::validate(const std::string& where) const
{
    auto check = [&](const char* name, double x, bool strictly_positive) {
        if (!std::isfinite(x) || x < 0 || (strictly_positive && !(x > 0)))
            throw ParameterError(where + ": " + name + " = " + format_value(x) + " must be a " +
                                 (strictly_positive ? "positive" : "non-negative") + " number");
    };
    check("width", width, true);
    check("height", height, true);
    if (cells_u < 4 || cells_u > 2000) throw ParameterError(where + ": cells along u = " + std::to_string(cells_u) + " must be in [4, 2000]");
    if (cells_v < 4 || cells_v > 2000) throw ParameterError(where + ": cells along v = " + std::to_string(cells_v) + " must be in [4, 2000]");
    check("particle mass", particle_mass, true);
    check("k_u", k_u, true);
    check("k_v", k_v, true);
    check("k_shear", k_shear, false);
    check("k_flex_u", k_flex_u, false);
    check("k_flex_v", k_flex_v, false);
    for (auto [name, d] : {std::pair{"d_u", d_u}, {"d_v", d_v}, {"d_shear", d_shear}, {"d_flex_u", d_flex_u}, {"d_flex_v", d_flex_v}})
        check(name, d, false);
}

ClothModel make_grid_spring_model(const ClothMesh& mesh, const GridSprings& s, const ModelOptions& opt)
{
    s.validate("grid springs");
    if (!mesh.grid.valid()) throw ParameterError("make_grid_spring_model: grid springs need a grid mesh");
    if (opt.bending == BendingModel::Quadratic)
        throw ParameterError("make_grid_spring_model: grid springs bend with flexion springs (BendingModel::Flexion)");
    ClothModel m;
    m.mass = Eigen::VectorXd::Constant(mesh.vertex_count(), s.particle_mass);
    m.air_damping = 0;
    m.contact_offset = 0;
    m.friction = 0;
    add_common(m, mesh, opt.contact_depth);
    m.edge_contact = opt.edge_contact;
    m.self_contact_distance = opt.self_collision ? kMinSelfContactDistance : 0.0;
    const auto& g = mesh.grid;
    for (int j = 0; j < g.nv; ++j)
        for (int i = 0; i < g.nu; ++i) {
            const int a = g.at(i, j);
            if (a < 0) continue;
            add_spring(m, mesh, a, g.at(i + 1, j), s.k_u, s.d_u, SpringKind::StretchU);
            add_spring(m, mesh, a, g.at(i, j + 1), s.k_v, s.d_v, SpringKind::StretchV);
            add_spring(m, mesh, a, g.at(i + 1, j + 1), s.k_shear, s.d_shear, SpringKind::Shear);
            if (g.at(i + 1, j) >= 0) add_spring(m, mesh, g.at(i + 1, j), g.at(i, j + 1), s.k_shear, s.d_shear, SpringKind::Shear);
            if (opt.bending != BendingModel::Quadratic) {
                add_spring(m, mesh, a, g.at(i + 2, j), s.k_flex_u, s.d_flex_u, SpringKind::FlexionU);
                add_spring(m, mesh, a, g.at(i, j + 2), s.k_flex_v, s.d_flex_v, SpringKind::FlexionV);
            }
        }
    m.description = "mass-spring grid (structural, shear, flexion springs) from explicit constants on its own grid";
    return m;
}

} // namespace drape::cloth
