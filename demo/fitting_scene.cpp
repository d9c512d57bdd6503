#include "demo/fitting_scene.hpp"

#include "engine/cloth/error.hpp"
#include "engine/cloth/model.hpp"
#include "engine/library/fabric_library.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <random>

namespace drape::demo {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string fmt(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.4g", v);
    return buf;
}

cloth::FabricParams continuum_of(const cloth::FabricPreset& preset)
{
    if (const auto* p = std::get_if<cloth::FabricParams>(&preset.fabric)) return *p;
    // The seed's grid constants describe one grid; their continuum equivalent
    // lets the same fabric drape any mesh.
    return cloth::continuum_from_seed(std::get<cloth::SeedParams>(preset.fabric));
}

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

/// Length of the closed curve r(theta) = rc + a (1 + sin(k theta)) [m].
double fluted_length(double rc, double a, int k)
{
    const int n = 720;
    double len = 0;
    for (int i = 0; i < n; ++i) {
        const double th = 2 * kPi * (i + 0.5) / n;
        const double r = rc + a * (1 + std::sin(k * th)), dr = a * k * std::cos(k * th);
        len += std::sqrt(r * r + dr * dr) * (2 * kPi / n);
    }
    return len;
}

} // namespace

std::string default_mannequin_path()
{
    return "/usr/share/assimp/models/Collada/human.zae";
}

Mannequin load_mannequin(const std::string& path, const importers::ImportOptions& opt)
{
    const importers::ImportedScene scene = importers::import_scene(path, opt);
    Mannequin m;
    m.path = path;
    m.mesh = scene.merged();
    const importers::AlignedBox b = m.mesh.bounds();
    const double h = b.max.z() - b.min.z();
    if (!(h > 0.5 && h < 2.5))
        throw ParameterError(path + ": mannequin is " + fmt(h) + " m tall after conversion (unit " +
                             importers::to_string(opt.unit) + ", up " + importers::to_string(opt.up) +
                             "); expected 0.5..2.5 m: give the file's unit and up axis");
    // Stand it on the floor, centred on the z axis.
    const Eigen::Vector3d shift(-(b.min.x() + b.max.x()) / 2, -(b.min.y() + b.max.y()) / 2, -b.min.z());
    m.mesh.X.rowwise() += shift.transpose();
    m.bounds = m.mesh.bounds();
    m.collider = std::make_shared<importers::MeshCollider>(m.mesh.X, m.mesh.F, 0.0);
    m.contact = std::make_shared<importers::MeshCollider>(m.mesh.X, m.mesh.F, Mannequin::kContactPadding);
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

Panel make_annulus(const Eigen::Vector2d& centre, double z, double inner_radius, double outer_radius, int segments,
                   int rings)
{
    if (!(inner_radius > 0) || !(outer_radius > inner_radius))
        throw ParameterError("annulus: radii must satisfy 0 < inner < outer (inner " + fmt(inner_radius) + " m, outer " +
                             fmt(outer_radius) + " m)");
    if (segments < 8) throw ParameterError("annulus: segments must be >= 8 (got " + std::to_string(segments) + ")");
    if (rings < 1) throw ParameterError("annulus: rings must be >= 1 (got " + std::to_string(rings) + ")");
    Panel p;
    const int n = segments * (rings + 1);
    p.X.resize(n, 3);
    const double q = std::pow(outer_radius / inner_radius, 1.0 / rings);
    const double dth = 2 * kPi / segments;
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
    if (name == "skirt") return Garment::Skirt;
    if (name == "tablecloth") return Garment::Tablecloth;
    throw ParameterError("garment: unknown \"" + name + "\" (expected skirt or tablecloth)");
}

std::string to_string(Garment g)
{
    return g == Garment::Skirt ? "skirt" : "tablecloth";
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
            const double want = 2 * kPi * rho;
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

Scene make_skirt_scene(std::shared_ptr<const Mannequin> m, const cloth::FabricPreset& fabric, const SkirtOptions& opt)
{
    if (!m) throw ParameterError("skirt: no mannequin");
    if (!(opt.length > 0)) throw ParameterError("skirt: length must be > 0 m (got " + fmt(opt.length) + ")");
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
        rings = std::max(2, int(std::ceil(std::log(r_out / r_in) / std::log(1 + 2 * kPi / opt.segments))));
    Panel p = make_annulus(s.waist.centre, zband, r_in, r_out, opt.segments, rings);
    cloth::FabricParams fp = continuum_of(fabric);
    s.fabric_name = fp.name;
    cloth::ClothMesh mesh = cloth::make_triangle_mesh(p.X, p.F, Eigen::Vector3d::UnitX());
    cloth::ClothModel model = cloth::make_model(mesh, fp, fabric.model);
    s.system = std::make_unique<cloth::ClothSystem>(std::move(mesh), std::move(model));
    for (int v : p.waistband) s.system->set_pinned(v, true);
    s.system->x = hang_skirt(*m, p, s.waist.centre, zband, r_in, opt);
    s.system->add_collider(m->contact);
    s.system->add_collider(std::make_shared<cloth::PlaneCollider>(Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitZ()));
    return s;
}

Scene make_tablecloth_scene(const cloth::FabricPreset& fabric, const Table& table, int grid, std::uint64_t seed)
{
    if (!(table.radius > 0) || !(table.height > 0) || !(table.cloth_diameter > 2 * table.radius))
        throw ParameterError("table: need radius > 0, height > 0 and a cloth wider than the top (radius " +
                             fmt(table.radius) + " m, height " + fmt(table.height) + " m, cloth " +
                             fmt(table.cloth_diameter) + " m)");
    Scene s;
    s.garment = Garment::Tablecloth;
    s.table = table;
    cloth::FabricParams fp = continuum_of(fabric);
    s.fabric_name = fp.name;
    cloth::ClothMesh mesh = cloth::make_disc(table.cloth_diameter, grid, 0.0);
    cloth::ClothModel model = cloth::make_model(mesh, fp, fabric.model);
    s.system = std::make_unique<cloth::ClothSystem>(std::move(mesh), std::move(model));
    // Start flat just above the top; a small random lift of the overhang
    // (modes k = 2..8) breaks the symmetry so the folds can choose where to form.
    const double R = table.cloth_diameter / 2;
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> U(0, 1);
    std::vector<double> amp, phase;
    for (int k = 2; k <= 8; ++k) {
        amp.push_back(U(rng));
        phase.push_back(2 * kPi * U(rng));
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

cloth::RestOptions demo_rest_options()
{
    cloth::RestOptions o;
    o.integrator = cloth::Integrator::Static;
    o.residual = 1e-4;
    o.max_newton = 800;
    return o;
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

std::vector<FabricChoice> available_fabrics(const std::string& library_path, const std::string& starter_dir,
                                            std::vector<std::string>* warnings)
{
    namespace fs = std::filesystem;
    std::vector<FabricChoice> out;
    auto warn = [&](const std::string& w) {
        if (warnings) warnings->push_back(w);
    };
    const std::string lib = library_path.empty() ? library::default_library_path() : library_path;
    std::error_code ec;
    if (fs::exists(lib, ec)) {
        try {
            library::FabricLibrary L(lib, library::FabricLibrary::Mode::ReadOnly);
            for (auto& r : L.list()) out.push_back({r.name, "library", r.preset});
        } catch (const std::exception& e) {
            warn(std::string("fabric library: ") + e.what());
        }
    }
    if (!starter_dir.empty() && fs::is_directory(starter_dir, ec)) {
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(starter_dir, ec))
            if (e.path().extension() == ".json") files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const auto& f : files) {
            try {
                cloth::FabricPreset p = cloth::load_fabric(f.string());
                const std::string name = library::preset_name(p);
                const bool dup = std::any_of(out.begin(), out.end(), [&](const FabricChoice& c) { return c.name == name; });
                if (!dup) out.push_back({name, "starter", std::move(p)});
            } catch (const std::exception& e) {
                warn(e.what());
            }
        }
    }
    try {
        out.push_back({"Seed paper, Table 1", "built-in", cloth::load_fabric("seed-table1")});
    } catch (const std::exception& e) {
        warn(e.what());
    }
    return out;
}

} // namespace drape::demo
