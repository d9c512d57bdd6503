#include "importers/garment_scene.hpp"

#include "engine/cloth/model.hpp"
#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>
#include <cstdio>
#include <chrono>
#include <cstdlib>
#include <random>

namespace drape::importers {

namespace {

/// A garment's model: the preset's options with self-contact on (folds of a
/// skirt and a tablecloth's overhang lie on each other; a drapemeter's do not).
cloth::ModelOptions garment_model_options(const fabric::FabricPreset& fabric)
{
    cloth::ModelOptions o = fabric.model;
    o.self_collision = true;
    return o;
}


/// Length of the closed curve r(theta) = rc + a (1 + sin(k theta)) [m].
double fluted_length(double rc, double a, int k)
{
    const int n = 720;
    double len = 0;
    for (int i = 0; i < n; ++i) {
        const double th = 2 * std::numbers::pi * (i + 0.5) / n;
        const double r = rc + a * (1 + std::sin(k * th)), dr = a * k * std::cos(k * th);
        len += std::sqrt(r * r + dr * dr) * (2 * std::numbers::pi / n);
    }
    return len;
}

} // namespace

Panel make_annulus(const Eigen::Vector2d& centre, double z, double inner_radius, double outer_radius, int segments,
                   int rings)
{
    if (!(inner_radius > 0) || !(outer_radius > inner_radius))
        throw ParameterError("annulus: radii must satisfy 0 < inner < outer (inner " + format_value(inner_radius) + " m, outer " +
                             format_value(outer_radius) + " m)");
    if (segments < 8) throw ParameterError("annulus: segments must be >= 8 (got " + std::to_string(segments) + ")");
    if (rings < 1) throw ParameterError("annulus: rings must be >= 1 (got " + std::to_string(rings) + ")");
    Panel p;
    const int n = segments * (rings + 1);
    p.X.resize(n, 3);
    const double q = std::pow(outer_radius / inner_radius, 1.0 / rings);
    const double dth = 2 * std::numbers::pi / segments;
    for (int k = 0; k <= rings; ++k) {
        const double r = inner_radius * std::pow(q, k);
        // Every other ring turned by half a segment: near-equilateral triangles.
        const double off = (k % 2) * 0.5 * dth;
        for (int j = 0; j < segments; ++j) {
            const double th = off + j * dth;
            p.X.row(k * segments + j) = Eigen::RowVector3d(centre.x() + r * std::cos(th), centre.y() + r * std::sin(th), z);
        }
    }
    p.F.resize(2 * segments * rings, 3);
    int t = 0;
    auto add = [&](int a, int b, int c) {
        // Counter-clockwise seen from +z, as ClothMesh wants.
        const Eigen::Vector3d ab = p.X.row(b) - p.X.row(a), ac = p.X.row(c) - p.X.row(a);
        if (ab.cross(ac).z() < 0) std::swap(b, c);
        p.F.row(t++) << a, b, c;
    };
    for (int k = 0; k < rings; ++k) {
        for (int j = 0; j < segments; ++j) {
            const int jn = (j + 1) % segments;
            const int a = k * segments + j, b = k * segments + jn;
            const int c = (k + 1) * segments + j, d = (k + 1) * segments + jn;
            if (k % 2 == 0) {
                // Outer ring turned +half a segment: c sits between a and b.
                add(a, b, c);
                add(b, d, c);
            } else {
                // Inner ring turned +half: d sits between a and b.
                add(a, b, d);
                add(a, d, c);
            }
        }
    }
    for (int j = 0; j < segments; ++j) p.waistband.push_back(j);
    return p;
}

Garment parse_garment(const std::string& name)
{
    if (name == "skirt" || name == "circle-skirt") return Garment::Skirt;
    if (name == "tablecloth") return Garment::Tablecloth;
    throw ParameterError("garment: unknown \"" + name + "\" (expected circle-skirt or tablecloth)");
}

std::string to_string(Garment g)
{
    switch (g) {
    case Garment::Skirt: return "skirt";
    case Garment::Tablecloth: return "tablecloth";
    case Garment::Mesh: return "mesh";
    }
    return "skirt";
}

namespace {
bool is_pin_name(const std::string& name)
{
    const std::string n = ascii_lower(name);
    return n.rfind("pin", 0) == 0 || n.rfind("waist", 0) == 0;
}
} // namespace

Scene make_garment_scene(std::shared_ptr<const Mannequin> m, const std::string& path, const fabric::FabricPreset& fabric,
                         const ImportOptions& opt)
{
    if (!m) throw ParameterError("garment: no mannequin");
    const ImportedScene scene = import_scene(path, opt);
    ImportedMesh all = scene.merged();
    weld_vertices(all.X, all.F);
    std::vector<Eigen::Vector3d> pin_points;
    std::string names;
    for (const auto& mesh : scene.meshes) {
        names += (names.empty() ? "" : ", ") + mesh.name;
        if (is_pin_name(mesh.name))
            for (Eigen::Index i = 0; i < mesh.X.rows(); ++i) pin_points.emplace_back(mesh.X.row(i).transpose());
    }
    if (pin_points.empty())
        throw FileError(path + ": no mesh, object or group named 'pin...' or 'waist...' (found: " + names +
                        "); declare the vertices that hold the garment, e.g. `g waist` before the waistband's faces in OBJ");
    Scene s;
    s.garment = Garment::Mesh;
    s.mannequin = m;
    s.waist = find_waist(*m);
    s.fabric_name = fabric.name;
    s.garment_name = path;
    cloth::ClothMesh mesh = cloth::make_triangle_mesh(all.X, all.F, Eigen::Vector3d::UnitX());
    cloth::ClothModel model = cloth::make_model(mesh, fabric.params, garment_model_options(fabric));
    s.system = std::make_unique<cloth::ClothSystem>(std::move(mesh), std::move(model));
    int pinned = 0;
    for (int i = 0; i < s.system->vertex_count(); ++i) {
        const Eigen::Vector3d x = s.system->x.row(i).transpose();
        for (const auto& p : pin_points)
            if ((p - x).squaredNorm() == 0.0) {
                s.system->set_pinned(i, true);
                ++pinned;
                break;
            }
    }
    if (pinned == s.system->vertex_count())
        throw FileError(path + ": every vertex is in a 'pin'/'waist' group: nothing is left to drape");
    s.system->add_collider(m->contact);
    s.system->add_collider(std::make_shared<cloth::PlaneCollider>(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
    return s;
}

std::shared_ptr<const MeshCollider> lower_body_collider(const Mannequin& m, double z_top, const Eigen::Vector2d& axis)
{
    // The hips: the largest closed torso section between the waist and the crotch.
    double keep = 0;
    for (double f = 0.40; f <= 0.62; f += 0.02) {
        const Girth g = measure_girth(m, m.bounds.min.z() + f * m.height(), 90);
        if (g.rays_hit == g.rays) keep = std::max(keep, g.max_radius);
    }
    keep += 0.05;
    std::vector<int> tris;
    for (Eigen::Index t = 0; t < m.mesh.F.rows(); ++t) {
        bool inside = true;
        for (int k = 0; k < 3 && inside; ++k) {
            const Eigen::Vector3d x = m.mesh.X.row(m.mesh.F(t, k)).transpose();
            inside = x.z() <= z_top && std::hypot(x.x() - axis.x(), x.y() - axis.y()) <= keep;
        }
        if (inside) tris.push_back(static_cast<int>(t));
    }
    cloth::Triangles F(static_cast<Eigen::Index>(tris.size()), 3);
    for (std::size_t i = 0; i < tris.size(); ++i) F.row(static_cast<Eigen::Index>(i)) = m.mesh.F.row(tris[i]);
    return std::make_shared<MeshCollider>(m.mesh.X, F, Mannequin::kContactPadding);
}

cloth::Positions hang_skirt(const Mannequin& m, const Panel& p, const Eigen::Vector2d& centre, double z_band,
                            double r_in, const SkirtOptions& opt)
{
    // Body radius below the waistband: the farthest torso surface seen from
    // the waist centre, kept non-decreasing downwards (a skirt hangs outside
    // everything above it), plus a clearance.
    const double clearance = 0.01; // [m]
    const double dz = 0.02;        // [m]
    std::vector<double> body;      // at z_band - i dz
    double running = 0;
    for (double z = z_band; z > z_band - opt.length - dz && z > m.bounds.min.z(); z -= dz) {
        const Girth g = measure_girth(m, z, 90);
        if (g.rays_hit == g.rays) running = std::max(running, g.max_radius);
        body.push_back(running + clearance);
    }
    auto body_at = [&](double z) {
        const int i = std::clamp(int((z_band - z) / dz), 0, int(body.size()) - 1);
        return body[std::size_t(i)];
    };
    const double slope = 0.05; // [rad] from vertical: the fabric chooses its own flare
    cloth::Positions x = p.X;
    // The pattern ring at radius rho hangs at slant distance s = rho - r_in
    // below the waistband; its length 2 pi rho is taken up by k outward folds
    // around a cone that clears the body, so springs start near their rest length.
    const int k = 8;
    std::vector<std::pair<double, double>> ring; // (rho, amplitude) cache per ring radius
    for (Eigen::Index i = 0; i < x.rows(); ++i) {
        const Eigen::Vector2d d = p.X.row(i).head<2>().transpose() - centre;
        const double rho = d.norm(), th = std::atan2(d.y(), d.x());
        const double sl = rho - r_in;
        if (sl < 1e-9) continue; // the waistband stays where it is pinned
        const double z = z_band - sl * std::cos(slope);
        const double rc = std::max(r_in + sl * std::sin(slope), body_at(z));
        double a = 0;
        auto hit = std::find_if(ring.begin(), ring.end(), [&](const auto& r) { return std::abs(r.first - rho) < 1e-9; });
        if (hit != ring.end()) a = hit->second;
        else {
            const double want = 2 * std::numbers::pi * rho;
            if (fluted_length(rc, 0, k) < want) {
                double lo = 0, hi = rho;
                for (int it = 0; it < 60; ++it) {
                    const double mid = (lo + hi) / 2;
                    (fluted_length(rc, mid, k) < want ? lo : hi) = mid;
                }
                a = lo;
            }
            ring.emplace_back(rho, a);
        }
        const double r = rc + a * (1 + std::sin(k * th));
        x(i, 0) = centre.x() + r * std::cos(th);
        x(i, 1) = centre.y() + r * std::sin(th);
        x(i, 2) = z;
    }
    return x;
}

Scene make_skirt_scene(std::shared_ptr<const Mannequin> m, const fabric::FabricPreset& fabric, const SkirtOptions& opt)
{
    if (!m) throw ParameterError("skirt: no mannequin");
    if (!(opt.length > 0)) throw ParameterError("skirt: length must be > 0 m (got " + format_value(opt.length) + ")");
    Scene s;
    s.garment = Garment::Skirt;
    s.mannequin = m;
    s.waist = find_waist(*m);
    const double zband = s.waist.z + opt.lift;
    // The waistband must clear the body where it is pinned, which sits a little above the waist.
    const Girth band = measure_girth(*m, zband);
    const double r_in = std::max(s.waist.max_radius, band.max_radius) + opt.ease;
    const double r_out = r_in + opt.length;
    int rings = opt.rings;
    if (rings <= 0)
        rings = std::max(2, int(std::ceil(std::log(r_out / r_in) / std::log(1 + 2 * std::numbers::pi / opt.segments))));
    Panel p = make_annulus(s.waist.centre, zband, r_in, r_out, opt.segments, rings);
    const cloth::FabricParams& fp = fabric.params; // a seed preset's continuum equivalent drapes any mesh
    s.fabric_name = fabric.name;
    s.garment_name = "circle skirt";
    cloth::ClothMesh mesh = cloth::make_triangle_mesh(p.X, p.F, Eigen::Vector3d::UnitX());
    cloth::ClothModel model = cloth::make_model(mesh, fp, garment_model_options(fabric));
    s.system = std::make_unique<cloth::ClothSystem>(std::move(mesh), std::move(model));
    for (int v : p.waistband) s.system->set_pinned(v, true);
    if (opt.start == SkirtOptions::Start::Gathered) s.system->x = hang_skirt(*m, p, s.waist.centre, zband, r_in, opt);
    s.system->add_collider(opt.start == SkirtOptions::Start::Flat ? lower_body_collider(*m, zband + 0.05, s.waist.centre) : m->contact);
    s.system->add_collider(std::make_shared<cloth::PlaneCollider>(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
    return s;
}

Scene make_tablecloth_scene(const fabric::FabricPreset& fabric, const Table& table, int grid, std::uint64_t seed)
{
    if (!(table.radius > 0) || !(table.height > 0) || !(table.cloth_diameter > 2 * table.radius))
        throw ParameterError("table: need radius > 0, height > 0 and a cloth wider than the top (radius " +
                             format_value(table.radius) + " m, height " + format_value(table.height) + " m, cloth " +
                             format_value(table.cloth_diameter) + " m)");
    Scene s;
    s.garment = Garment::Tablecloth;
    s.table = table;
    const cloth::FabricParams& fp = fabric.params; // a seed preset's continuum equivalent drapes any mesh
    s.fabric_name = fabric.name;
    s.garment_name = "tablecloth";
    cloth::ClothMesh mesh = cloth::make_disc(table.cloth_diameter, grid, 0.0);
    cloth::ClothModel model = cloth::make_model(mesh, fp, garment_model_options(fabric));
    s.system = std::make_unique<cloth::ClothSystem>(std::move(mesh), std::move(model));
    // Start flat just above the top; a small random lift of the overhang
    // (modes k = 2..8) breaks the symmetry so the folds can choose where to form.
    const double R = table.cloth_diameter / 2;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> U(0, 1);
    std::vector<double> amp, phase;
    for (int k = 2; k <= 8; ++k) {
        amp.push_back(U(rng));
        phase.push_back(2 * std::numbers::pi * U(rng));
    }
    const double lift = 2e-3; // [m]
    for (int i = 0; i < s.system->vertex_count(); ++i) {
        const double x = s.system->x(i, 0), y = s.system->x(i, 1);
        const double r = std::hypot(x, y), th = std::atan2(y, x);
        double dz = 0;
        for (std::size_t k = 0; k < amp.size(); ++k) dz += amp[k] * std::cos(double(k + 2) * th + phase[k]);
        const double w = r > table.radius ? std::pow((r - table.radius) / (R - table.radius), 2) : 0.0;
        s.system->x(i, 2) = table.height + s.system->model().contact_offset + 1e-6 + lift * w * dz / double(amp.size());
    }
    // A round table is a pedestal: a vertical cylinder with a flat top.
    s.system->add_collider(std::make_shared<cloth::PedestalCollider>(Eigen::Vector3d(0, 0, table.height), table.radius,
                                                                     table.height, 2e-3));
    s.system->add_collider(std::make_shared<cloth::PlaneCollider>(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
    return s;
}

cloth::SolverStatus drape_to_rest(Scene& scene, const cloth::RestOptions& opt, const Settling& settling)
{
    if (scene.garment != Garment::Skirt) return cloth::run_to_rest(*scene.system, opt);
    return settle_to_rest(*scene.system, opt, settling);
}

cloth::SolverStatus settle_to_rest(cloth::ClothSystem& s, const cloth::RestOptions& opt, const Settling& settling)
{
    if (settling.duration <= 0) return cloth::run_to_rest(s, opt);
    if (!(settling.dt > 0) || !(settling.damping_rate >= 0) || settling.iterations < 1)
        throw ParameterError("drape_to_rest: settling needs dt > 0, damping rate >= 0 and at least one iteration");
    const auto t0 = std::chrono::steady_clock::now();
    cloth::Stepper stepper(s, cloth::Integrator::ImplicitEuler);
    stepper.set_implicit_iterations(settling.iterations);
    const double air = s.model().air_damping;
    s.model().air_damping = std::max(air, settling.damping_rate);
    cloth::SolverStatus drop;
    s.v.setZero();
    const double t_end = s.time + settling.duration;
    bool stopped = false;
    while (s.time < t_end - 1e-9 && !stopped) {
        if (!stepper.step(settling.dt)) break;
        ++drop.steps;
        if (opt.cancel && opt.cancel->load()) stopped = true;
        if (opt.progress) {
            drop.newton_iterations = stepper.linear_solves();
            drop.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            drop.sim_time = s.time;
            if (!opt.progress(drop)) stopped = true;
        }
    }
    s.model().air_damping = air;
    s.v.setZero();
    if (stopped) {
        drop.outcome = cloth::SolverStatus::Outcome::Cancelled;
        drop.newton_iterations = stepper.linear_solves();
        drop.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        return drop;
    }
    cloth::SolverStatus st = cloth::run_to_rest(s, opt);
    st.newton_iterations += stepper.linear_solves();
    st.steps += drop.steps;
    st.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return st;
}

cloth::RestOptions garment_rest_options()
{
    cloth::RestOptions o;
    o.integrator = cloth::Integrator::Static;
    o.residual = 1e-4;
    o.max_newton = 2000; // the cotton skirt needs ~1400 after its fall (docs/garments.md)
    return o;
}

} // namespace drape::importers
