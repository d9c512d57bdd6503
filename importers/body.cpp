#include "importers/body.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <limits>

namespace drape::importers {

namespace {

constexpr double kPi = std::numbers::pi;

/// Segments of the section of triangle mesh (X, F) with the plane z = h, as 2-D points pairs.
std::vector<std::array<Eigen::Vector2d, 2>> section(const cloth::Positions& X, const cloth::Triangles& F, double h)
{
    std::vector<std::array<Eigen::Vector2d, 2>> segs;
    for (Eigen::Index t = 0; t < F.rows(); ++t) {
        Eigen::Vector2d pts[3];
        int k = 0;
        for (int e = 0; e < 3 && k < 3; ++e) {
            const Eigen::Vector3d a = X.row(F(t, e)), b = X.row(F(t, (e + 1) % 3));
            const double da = a.z() - h, db = b.z() - h;
            // Half-open test so a vertex exactly on the plane counts once.
            if ((da < 0) != (db < 0)) {
                const double s = da / (da - db);
                const Eigen::Vector3d p = a + s * (b - a);
                pts[k++] = p.head<2>();
            }
        }
        if (k == 2) segs.push_back({pts[0], pts[1]});
    }
    return segs;
}

} // namespace

std::string default_mannequin_path()
{
    return "/usr/share/assimp/models/Collada/human.zae";
}

Mannequin load_mannequin(const std::string& path, const ImportOptions& opt)
{
    const ImportedScene scene = import_scene(path, opt);
    Mannequin m;
    m.path = path;
    m.mesh = scene.merged();
    const AlignedBox b = m.mesh.bounds();
    const double h = b.max.z() - b.min.z();
    if (!(h > 0.5 && h < 2.5))
        throw ParameterError(path + ": mannequin is " + format_value(h) + " m tall after conversion (unit " +
                             to_string(opt.unit) + ", up " + to_string(opt.up) +
                             "); expected 0.5..2.5 m: give the file's unit and up axis");
    // Stand it on the floor, centred on the z axis.
    const Eigen::Vector3d shift(-(b.min.x() + b.max.x()) / 2, -(b.min.y() + b.max.y()) / 2, -b.min.z());
    m.mesh.X.rowwise() += shift.transpose();
    m.bounds = m.mesh.bounds();
    m.collider = std::make_shared<MeshCollider>(m.mesh.X, m.mesh.F, 0.0);
    m.contact = std::make_shared<MeshCollider>(m.mesh.X, m.mesh.F, Mannequin::kContactPadding);
    return m;
}

Girth measure_girth(const Mannequin& m, double z, int rays)
{
    Girth g;
    g.z = z;
    g.rays = rays;
    const auto segs = section(m.mesh.X, m.mesh.F, z);
    if (segs.empty()) return g;
    // Torso centre: the extent of the section near the body's middle. Arms and
    // hands hang farther out than 15 % of the height from the axis only partly,
    // so the extent is taken from the points closest to the axis first.
    const double half = 0.15 * m.height();
    Eigen::Vector2d lo(1e9, 1e9), hi(-1e9, -1e9);
    for (const auto& s : segs)
        for (const auto& p : s)
            if (std::abs(p.x()) < half && std::abs(p.y()) < half) {
                lo = lo.cwiseMin(p);
                hi = hi.cwiseMax(p);
            }
    if (lo.x() > hi.x()) return g;
    g.centre = (lo + hi) / 2;
    double sum = 0;
    for (int k = 0; k < rays; ++k) {
        const double th = 2 * kPi * k / rays;
        const Eigen::Vector2d d(std::cos(th), std::sin(th));
        double best = std::numeric_limits<double>::infinity();
        for (const auto& s : segs) {
            // Solve centre + t d = a + u (b - a).
            const Eigen::Vector2d e = s[1] - s[0], w = s[0] - g.centre;
            const double den = d.x() * (-e.y()) - d.y() * (-e.x());
            if (std::abs(den) < 1e-15) continue;
            const double t = (w.x() * (-e.y()) - w.y() * (-e.x())) / den;
            const double u = (d.x() * w.y() - d.y() * w.x()) / den;
            if (t > 0 && u >= 0 && u <= 1) best = std::min(best, t);
        }
        if (std::isfinite(best)) {
            ++g.rays_hit;
            sum += best;
            g.max_radius = std::max(g.max_radius, best);
        }
    }
    if (g.rays_hit > 0) g.mean_radius = sum / g.rays_hit;
    return g;
}

Girth find_waist(const Mannequin& m)
{
    const double z0 = m.bounds.min.z(), h = m.height();
    Girth best;
    bool have = false;
    for (int i = 0; i <= 40; ++i) {
        const double z = z0 + h * (0.56 + 0.10 * i / 40.0);
        const Girth g = measure_girth(m, z);
        if (g.rays_hit < g.rays) continue; // not a closed torso section
        if (!have || g.mean_radius < best.mean_radius) {
            best = g;
            have = true;
        }
    }
    if (!have)
        throw ParameterError(m.path + ": no closed torso section between 56 % and 66 % of the height; "
                             "is the mannequin standing (up axis)?");
    return best;
}

Penetration body_penetration(const Mannequin& m, const cloth::Positions& x)
{
    Penetration p;
    p.min_distance = std::numeric_limits<double>::infinity();
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
        const double d = m.collider->signed_distance(x.row(i).transpose());
        if (d < 0) ++p.inside;
        if (d < p.min_distance) {
            p.min_distance = d;
            p.worst_vertex = int(i);
        }
    }
    return p;
}

} // namespace drape::importers
