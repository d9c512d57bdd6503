#include "engine/cloth/model.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <map>

namespace drape::cloth {

namespace {

constexpr double kEulerPinned = 9.869604401089358; // pi^2: a strip with pinned ends

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

/// Grid-line stencil through (a, b, c) with divided-difference weights of their
/// material spacings; skipped when a node is missing or was moved off its grid node.
void add_line_stencil(ClothModel& m, const ClothMesh& mesh, int a, int b, int c, double B, double cb, double hu, double hv,
                      int axis)
{
    if (a < 0 || b < 0 || c < 0) return;
    for (int i : {a, b, c})
        if (!mesh.on_grid_line[static_cast<std::size_t>(i)]) return;
    const double sa = mesh.uv(a, axis), sb = mesh.uv(b, axis), sc = mesh.uv(c, axis);
    BendStencil st;
    st.n = 3;
    st.v[0] = a;
    st.v[1] = b;
    st.v[2] = c;
    st.w[0] = 2.0 / ((sb - sa) * (sc - sa));
    st.w[2] = 2.0 / ((sc - sb) * (sc - sa));
    st.w[1] = -(st.w[0] + st.w[2]);
    st.k = B * hu * hv;
    st.d = cb * hu * hv;
    m.bends.push_back(st);
}

/// Twist stencil on a grid cell: the mixed derivative x_uv = (x11 - x10 - x01 + x00)/(hu hv),
/// energy B_t x_uv^2 hu hv (the 2 B_t kappa_uv^2 / 2 term of a plate with no Poisson
/// coupling). Without it a fold running diagonally to the grid would cost half the
/// bending energy of one along a grid line. B_t = sqrt(B_u B_v), the usual closure for
/// orthotropic fabrics.
void add_twist_stencil(ClothModel& m, const ClothMesh& mesh, int a, int b, int c, int d, double Bt, double cb, double hu, double hv)
{
    if (a < 0 || b < 0 || c < 0 || d < 0) return;
    for (int i : {a, b, c, d})
        if (!mesh.on_grid_line[static_cast<std::size_t>(i)]) return;
    BendStencil st;
    st.n = 4;
    const int ids[4] = {a, b, c, d};
    const double w[4] = {1, -1, -1, 1};
    for (int i = 0; i < 4; ++i) {
        st.v[i] = ids[i];
        st.w[i] = w[i] / (hu * hv);
    }
    st.k = 2 * Bt * hu * hv;
    st.d = 2 * cb * hu * hv;
    m.bends.push_back(st);
}

} // namespace

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
    add_common(m, mesh, opt.contact_depth);
    m.edge_contact = opt.edge_contact;
    const double Eu = p[Param::StretchWarp], Ev = p[Param::StretchWeft], G = p[Param::Shear];
    const double Bu = p[Param::BendWarp], Bv = p[Param::BendWeft];
    const double cs = p[Param::DampStretch], csh = p[Param::DampShear], cb = p[Param::DampBend];
    const bool quadratic = opt.bending != BendingModel::Flexion;
    if (mesh.grid.valid()) {
        const auto& g = mesh.grid;
        const double hu = g.hu, hv = g.hv;
        const double ku = std::max(Eu - G * hu * hu / (hv * hv), 0.5 * Eu) * hv / hu;
        const double kv = std::max(Ev - G * hv * hv / (hu * hu), 0.5 * Ev) * hu / hv;
        const double ksh = (hu * hu + hv * hv) / (2 * hu * hv);
        for (int j = 0; j < g.nv; ++j)
            for (int i = 0; i < g.nu; ++i) {
                const int a = g.at(i, j);
                if (a < 0) continue;
                add_spring(m, mesh, a, g.at(i + 1, j), ku, cs * hv / hu, SpringKind::StretchU);
                add_spring(m, mesh, a, g.at(i, j + 1), kv, cs * hu / hv, SpringKind::StretchV);
                add_spring(m, mesh, a, g.at(i + 1, j + 1), G * ksh, csh * ksh, SpringKind::Shear);
                if (g.at(i + 1, j) >= 0) add_spring(m, mesh, g.at(i + 1, j), g.at(i, j + 1), G * ksh, csh * ksh, SpringKind::Shear);
                if (quadratic) {
                    add_line_stencil(m, mesh, g.at(i - 1, j), a, g.at(i + 1, j), Bu, cb, hu, hv, 0);
                    add_line_stencil(m, mesh, g.at(i, j - 1), a, g.at(i, j + 1), Bv, cb, hu, hv, 1);
                    add_twist_stencil(m, mesh, a, g.at(i + 1, j), g.at(i, j + 1), g.at(i + 1, j + 1), std::sqrt(Bu * Bv), cb, hu, hv);
                }
            }
        m.description = "grid mass-spring model (stretch, shear, quadratic bending) from continuum parameters";
        if (opt.buckling == ModelOptions::Buckling::Euler) {
            // The Euler load of the strip each spring stands for (ModelOptions::buckling):
            // warp and weft springs a strip of width hv (hu) and length hu (hv); the shear
            // diagonals a strip of length L = sqrt(hu^2 + hv^2) and width hu hv / L,
            // bending with the twist closure sqrt(Bu Bv).
            const double L2 = hu * hu + hv * hv;
            for (auto& sp : m.springs) {
                if (sp.kind == SpringKind::StretchU) sp.fc = kEulerPinned * Bu * hv / (hu * hu);
                else if (sp.kind == SpringKind::StretchV) sp.fc = kEulerPinned * Bv * hu / (hv * hv);
                else if (sp.kind == SpringKind::Shear) sp.fc = kEulerPinned * std::sqrt(Bu * Bv) * (hu * hv / std::sqrt(L2)) / L2;
            }
        }
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
    auto tri_area = [&](int t) {
        const Eigen::Vector2d p0 = mesh.uv.row(mesh.F(t, 0)), p1 = mesh.uv.row(mesh.F(t, 1)), p2 = mesh.uv.row(mesh.F(t, 2));
        return 0.5 * std::abs((p1 - p0).x() * (p2 - p0).y() - (p1 - p0).y() * (p2 - p0).x());
    };
    const double E = 0.5 * (Eu + Ev);
    for (const auto& [edge, tris] : edge_tris) {
        const auto [a, b] = edge;
        double A = 0;
        for (int t : tris) A += tri_area(t);
        const double len2 = (mesh.uv.row(a) - mesh.uv.row(b)).squaredNorm();
        if (len2 <= 0) throw ParameterError("make_model: zero-length edge between vertices " + std::to_string(a) + " and " + std::to_string(b));
        add_spring(m, mesh, a, b, E * A / len2, cs * A / len2, SpringKind::Edge);
        if (opt.buckling == ModelOptions::Buckling::Euler) {
            // The Euler load of the strip along the edge (ModelOptions::buckling):
            // width A / L (the edge's share of its triangles), bending along the edge.
            const Eigen::Vector2d d = (mesh.uv.row(b) - mesh.uv.row(a)).transpose();
            const double c2 = d.x() * d.x() / len2, s2 = d.y() * d.y() / len2;
            m.springs.back().fc = kEulerPinned * (Bu * c2 + Bv * s2) * (A / std::sqrt(len2)) / len2;
        }
        if (tris.size() != 2 || !quadratic) continue;
        // The lambda takes copies: clang before 16 cannot capture structured bindings.
        auto opposite = [&, ea = a, eb = b](int t) {
            for (int c = 0; c < 3; ++c)
                if (mesh.F(t, c) != ea && mesh.F(t, c) != eb) return mesh.F(t, c);
            return -1;
        };
        const int c = opposite(tris[0]), d = opposite(tris[1]);
        const int ids[4] = {a, b, c, d};
        Eigen::Matrix<double, 3, 4> C;
        for (int i = 0; i < 4; ++i) C.col(i) << 1.0, mesh.uv(ids[i], 0), mesh.uv(ids[i], 1);
        Eigen::FullPivLU<Eigen::Matrix<double, 3, 4>> lu(C);
        const Eigen::Matrix<double, 4, Eigen::Dynamic> ker = lu.kernel();
        if (ker.cols() != 1) continue; // degenerate hinge (collinear material points)
        Eigen::Vector4d w = ker.col(0);
        const Eigen::Vector2d pa = mesh.uv.row(a), pb = mesh.uv.row(b);
        Eigen::Vector2d t = (pb - pa).normalized();
        const Eigen::Vector2d across(-t.y(), t.x());
        double norm = 0;
        for (int i = 0; i < 4; ++i) {
            const double s = (Eigen::Vector2d(mesh.uv.row(ids[i])) - pa).dot(across);
            norm += w(i) * 0.5 * s * s;
        }
        if (std::abs(norm) < 1e-300) continue;
        w /= norm;
        const double c2 = across.x() * across.x(), s2 = across.y() * across.y();
        const double Bphi = Bu * c2 + Bv * s2;
        const double Ahinge = (tri_area(tris[0]) + tri_area(tris[1])) / 3.0;
        BendStencil st;
        st.n = 4;
        for (int i = 0; i < 4; ++i) {
            st.v[i] = ids[i];
            st.w[i] = w(i);
        }
        st.k = Bphi * Ahinge;
        st.d = cb * Ahinge;
        m.bends.push_back(st);
    }
    m.description = "triangle mass-spring model (edge springs, quadratic hinge bending) from continuum parameters";
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
