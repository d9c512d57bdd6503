#include "measured.hpp"

#include "engine/cloth/error.hpp"
#include "engine/cloth/fabric_io.hpp"
#include "engine/cloth/units.hpp"

#include <nlohmann/json.hpp>

#ifdef DRAPE_ESTIMATE_HAVE_CAPTURE
#include "engine/capture/measure.hpp"
#endif

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <numbers>
#include <random>
#include <sstream>

namespace drape::estimate {

using nlohmann::json;
namespace fs = std::filesystem;

Eigen::Vector2d PinholeCamera::project(const Eigen::Vector3d& X) const
{
    const Eigen::Vector3d c = R * X + t;
    return {fx * c.x() / c.z() + cx, fy * c.y() / c.z() + cy};
}

cloth::DrapeSetup MeasuredDrape::setup(int grid, std::uint64_t seed) const
{
    cloth::DrapeSetup s;
    s.sample_diameter = sample_diameter;
    s.disc_diameter = disc_diameter;
    s.pedestal_height = pedestal_height;
    s.grid = grid;
    s.seed = seed;
    s.slice_depths = depths();
    if (s.slice_depths.empty()) s.slice_depths = {0.005};
    return s;
}

int measured_fold_branch(double node_count)
{
    const long n = std::isfinite(node_count) ? std::lround(node_count) : 0;
    return n >= 2 && n <= 16 ? static_cast<int>(n) : 0;
}

std::vector<double> MeasuredDrape::depths() const
{
    std::vector<double> d;
    for (const auto& c : contours) d.push_back(c.depth_m);
    return d;
}

namespace {

const json& field(const json& j, const std::string& key, const std::string& where)
{
    if (!j.is_object() || !j.contains(key)) throw FileError(where + ": missing field '" + key + "'");
    return j.at(key);
}

double number(const json& j, const std::string& key, const std::string& where)
{
    const json& v = field(j, key, where);
    if (!v.is_number()) throw FileError(where + ": field '" + key + "' = " + v.dump() + " is not a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) throw FileError(where + ": field '" + key + "' is not finite");
    return x;
}

double positive(const json& j, const std::string& key, const std::string& where)
{
    const double x = number(j, key, where);
    if (!(x > 0)) throw ParameterError(where + ": field '" + key + "' = " + format_double(x) + " must be positive");
    return x;
}

std::optional<PinholeCamera> read_camera(const json& cams, const std::string& name, const std::string& where)
{
    if (!cams.is_object() || !cams.contains(name)) return std::nullopt;
    const json& c = cams[name];
    const std::string w = where + ": cameras." + name;
    PinholeCamera cam;
    cam.fx = positive(c, "fx", w);
    cam.fy = positive(c, "fy", w);
    cam.cx = number(c, "cx", w);
    cam.cy = number(c, "cy", w);
    const json& R = field(c, "R_world_to_cam", w);
    const json& t = field(c, "t_world_to_cam_mm", w);
    if (!R.is_array() || R.size() != 3 || !t.is_array() || t.size() != 3)
        throw FileError(w + ": R_world_to_cam must be 3x3 and t_world_to_cam_mm a 3-vector");
    for (int i = 0; i < 3; ++i) {
        if (!R[i].is_array() || R[i].size() != 3 || !t[i].is_number())
            throw FileError(w + ": R_world_to_cam / t_world_to_cam_mm hold non-numbers");
        for (int k = 0; k < 3; ++k) cam.R(i, k) = R[i][k].get<double>();
        cam.t(i) = t[i].get<double>() * 1e-3;
    }
    if (c.contains("image_size") && c["image_size"].is_array() && c["image_size"].size() == 2) {
        cam.width = c["image_size"][0].get<int>();
        cam.height = c["image_size"][1].get<int>();
    } else if (c.contains("width") && c.contains("height")) {
        cam.width = c["width"].get<int>();
        cam.height = c["height"].get<int>();
    }
    return cam;
}

} // namespace

MeasuredDrape load_record(const std::string& dir, bool use_photos)
{
    const fs::path root(dir);
    if (!fs::is_directory(root)) throw FileError(dir + ": not a record folder");
    const std::string meta_path = (root / "meta.json").string();
    json meta;
    try {
        meta = json::parse(cloth::read_file(meta_path));
    } catch (const json::parse_error& e) {
        throw FileError(meta_path + ": not valid JSON (" + e.what() + ")");
    }
    MeasuredDrape m;
    m.source = dir;
    m.id = meta.contains("specimen_id") && meta["specimen_id"].is_string() ? meta["specimen_id"].get<std::string>()
                                                                          : root.filename().string();
    const json& conf = field(meta, "configuration", meta_path);
    const std::string cw = meta_path + ": configuration";
    m.sample_diameter = positive(conf, "specimen_diameter_D1_mm", cw) * 1e-3;
    m.disc_diameter = positive(conf, "support_disc_diameter_D2_mm", cw) * 1e-3;
    m.pedestal_height = conf.contains("pedestal_height_mm") ? positive(conf, "pedestal_height_mm", cw) * 1e-3 : 0.12;
    if (m.sample_diameter <= m.disc_diameter)
        throw ParameterError(cw + ": specimen_diameter_D1_mm = " + format_double(m.sample_diameter * 1e3) +
                             " must exceed support_disc_diameter_D2_mm = " + format_double(m.disc_diameter * 1e3));
    const json& fab = field(meta, "fabric", meta_path);
    const std::string fw = meta_path + ": fabric";
    m.areal_density = positive(fab, "areal_density_g_m2", fw) * 1e-3;
    m.thickness = fab.contains("thickness_mm") ? positive(fab, "thickness_mm", fw) * 1e-3 : 0.5e-3;
    if (meta.contains("lab_drape_coefficient_percent"))
        m.drape_coefficient_percent = number(meta, "lab_drape_coefficient_percent", meta_path);
    if (meta.contains("node_count")) {
        m.node_count = static_cast<int>(number(meta, "node_count", meta_path));
        m.node_source = "meta.json";
    }
    std::string contour_file = "contours.csv";
    if (meta.contains("contours") && meta["contours"].is_object()) {
        const json& c = meta["contours"];
        if (c.contains("file") && c["file"].is_string()) contour_file = c["file"].get<std::string>();
        if (c.contains("repeatability_sigma_mm")) m.laser_sigma_m = positive(c, "repeatability_sigma_mm", meta_path + ": contours") * 1e-3;
    }
    if (meta.contains("cameras")) m.top_camera = read_camera(meta["cameras"], "top", meta_path);
    if (m.top_camera) {
        std::string img = "top.jpg";
        const json& c = meta["cameras"]["top"];
        if (c.contains("image") && c["image"].is_string()) img = c["image"].get<std::string>();
        if (fs::exists(root / img)) m.top_photo = (root / img).string();
    }

    // contours.csv: depth_mm,theta_deg,x_mm,y_mm
    const std::string cpath = (root / contour_file).string();
    std::istringstream in(cloth::read_file(cpath));
    std::string line;
    std::map<double, std::vector<std::pair<double, double>>> by_depth; // depth mm -> (theta deg, r m)
    int lineno = 0;
    while (std::getline(in, line)) {
        ++lineno;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        if (lineno == 1 && line.find("depth") != std::string::npos) continue;
        double v[4];
        std::istringstream ls(line);
        std::string cell;
        for (int i = 0; i < 4; ++i) {
            if (!std::getline(ls, cell, ',')) throw FileError(cpath + ":" + std::to_string(lineno) + ": expected 4 columns");
            try {
                std::size_t used = 0;
                v[i] = std::stod(cell, &used);
            } catch (const std::exception&) {
                throw FileError(cpath + ":" + std::to_string(lineno) + ": '" + cell + "' is not a number");
            }
            if (!std::isfinite(v[i])) throw FileError(cpath + ":" + std::to_string(lineno) + ": non-finite value");
        }
        by_depth[v[0]].push_back({v[1], std::hypot(v[2], v[3]) * 1e-3});
    }
    for (auto& [depth_mm, rows] : by_depth) {
        if (rows.size() < 8) throw FileError(cpath + ": depth " + format_double(depth_mm) + " mm has only " + std::to_string(rows.size()) + " rows");
        const int N = static_cast<int>(rows.size());
        const double step = 360.0 / N;
        MeasuredContour c;
        c.depth_m = depth_mm * 1e-3;
        c.profile.r.assign(N, std::numeric_limits<double>::quiet_NaN());
        for (const auto& [th, r] : rows) {
            const double kk = th / step;
            const int k = static_cast<int>(std::lround(kk));
            if (std::abs(kk - k) > 1e-3 || k < 0 || k >= N)
                throw FileError(cpath + ": depth " + format_double(depth_mm) + " mm: theta_deg = " + format_double(th) +
                                " is not on the regular " + format_double(step) + " degree grid");
            c.profile.r[k] = r;
        }
        if (!c.profile.complete()) throw FileError(cpath + ": depth " + format_double(depth_mm) + " mm has missing or repeated angles");
        m.contours.push_back(std::move(c));
    }
    if (m.contours.empty()) throw FileError(cpath + ": no contours");
#ifdef DRAPE_ESTIMATE_HAVE_CAPTURE
    if (use_photos && m.node_count < 0) {
        // The photos: node count from the top view's perspective-corrected
        // outline, lowest hem point from the side view (capture layer).
        try {
            const capture::Record rec = capture::read_record(root);
            const capture::MeasureOptions mo;
            const capture::Measurement cm = capture::measure_record(rec, mo);
            if (cm.top.measured) {
                m.node_count = cm.top.metrics.node_count;
                m.node_source = "top photo (capture layer)";
                m.node_metric_options = mo.metrics;
                m.photo_drape_coefficient_percent = cm.top.metrics.drape_coefficient_percent;
            }
            if (cm.side.measured && std::isfinite(cm.side.hem_min_z)) {
                m.hem_min_z = cm.side.hem_min_z;
                m.hem_from_side_view = true;
            }
            for (const auto& w : cm.warnings) m.notes.push_back("capture: " + w);
            for (const auto& w : cm.not_measured) m.notes.push_back("capture: not measured: " + w);
        } catch (const std::exception& e) {
            m.notes.push_back(std::string("capture failed, contours only: ") + e.what());
        }
    }
#else
    (void)use_photos;
#endif
    if (m.node_count < 0) m.node_source = "crests of the deepest contour";
    return m;
}

MeasuredDrape synthesize_record(const cloth::DrapeResult& r, const cloth::DrapeSetup& setup, const cloth::FabricParams& p,
                                double laser_sigma_m, std::uint64_t noise_seed, const std::string& id)
{
    MeasuredDrape m;
    m.id = id;
    m.source = "synthetic";
    m.sample_diameter = setup.sample_diameter;
    m.disc_diameter = setup.disc_diameter;
    m.pedestal_height = setup.pedestal_height;
    m.areal_density = p[cloth::Param::AreaDensity];
    m.thickness = p[cloth::Param::Thickness];
    m.drape_coefficient_percent = r.metrics.drape_coefficient_percent;
    m.laser_sigma_m = laser_sigma_m;
    m.hem_min_z = r.hem.min_z;
    m.node_source = "crests of the deepest contour";
    std::mt19937_64 rng(noise_seed);
    std::normal_distribution<double> g(0.0, 1.0);
    for (const auto& s : r.slices) {
        if (!s.profile.complete()) break; // the profiler reports a depth only where the cut closes
        MeasuredContour c{s.depth_m, s.profile};
        for (double& x : c.profile.r) x += laser_sigma_m * g(rng);
        m.contours.push_back(std::move(c));
    }
    return m;
}

ContourFeatures contour_features(const cloth::RadialProfile& p, double depth_m, int harmonics)
{
    ContourFeatures f;
    f.depth_m = depth_m;
    f.closed = p.complete();
    int hits = 0;
    for (double r : p.r) hits += std::isfinite(r) ? 1 : 0;
    if (hits < 2 * harmonics + 2) return f;
    f.series = cloth::fourier_fit(p, harmonics);
    f.mean_radius_m = f.series.a0;
    double ss = 0;
    for (double r : p.r)
        if (std::isfinite(r)) ss += (r - f.series.a0) * (r - f.series.a0);
    f.fold_rms_m = std::sqrt(ss / hits);
    f.cos2_m = f.series.a.size() >= 2 ? f.series.a[1] : 0;
    f.cos4_m = f.series.a.size() >= 4 ? f.series.a[3] : 0;
    for (int k = 1; k <= f.series.harmonics(); ++k) f.magnitudes_m.push_back(f.series.magnitude(k));
    if (f.closed) {
        // The shared node detector works on the smoothed series (as drape_metrics does).
        const cloth::MetricOptions mo;
        cloth::DrapeMetrics dm;
        dm.fourier = cloth::fourier_fit(p, mo.smoothing_harmonics);
        cloth::find_nodes(p, mo, dm);
        f.node_count = dm.node_count;
    }
    return f;
}

Eigen::Vector2d recentre_stack(std::vector<cloth::RadialProfile>& profiles)
{
    Eigen::Vector2d sum = Eigen::Vector2d::Zero();
    int n = 0;
    for (const auto& p : profiles) {
        if (!p.complete()) continue;
        const cloth::Polygon2 poly = cloth::polygon_from_profile(p);
        double a = 0;
        Eigen::Vector2d c = Eigen::Vector2d::Zero();
        for (std::size_t i = 0; i < poly.size(); ++i) {
            const Eigen::Vector2d& p0 = poly[i];
            const Eigen::Vector2d& p1 = poly[(i + 1) % poly.size()];
            const double cr = p0.x() * p1.y() - p1.x() * p0.y();
            a += cr;
            c += cr * (p0 + p1);
        }
        if (std::abs(a) < 1e-12) continue;
        sum += c / (3 * a);
        ++n;
    }
    if (n == 0) return Eigen::Vector2d::Zero();
    const Eigen::Vector2d shift = sum / n;
    for (auto& p : profiles) {
        if (!p.complete()) continue;
        cloth::Polygon2 poly = cloth::polygon_from_profile(p);
        for (auto& v : poly) v -= shift;
        p = cloth::radial_profile(poly, p.size());
    }
    return shift;
}

namespace {
/// Features of a contour stack at the given depths, re-centred when asked.
std::vector<ContourFeatures> stack_features(std::vector<cloth::RadialProfile> profiles, const std::vector<double>& depths,
                                            bool recentre, Eigen::Vector2d& offset)
{
    offset.setZero();
    if (recentre) offset = recentre_stack(profiles);
    std::vector<ContourFeatures> out;
    for (std::size_t i = 0; i < profiles.size(); ++i) out.push_back(contour_features(profiles[i], depths[i]));
    return out;
}
} // namespace

DrapeFeatures drape_features(const MeasuredDrape& m)
{
    DrapeFeatures f;
    f.drape_coefficient_percent = m.drape_coefficient_percent;
    f.hem_min_z = m.hem_min_z;
    std::vector<cloth::RadialProfile> profiles;
    std::vector<double> depths;
    for (const auto& c : m.contours) {
        profiles.push_back(c.profile);
        depths.push_back(c.depth_m);
    }
    f.contours = stack_features(std::move(profiles), depths, m.recentre_contours, f.axis_offset_m);
    if (m.node_count >= 0) f.node_count = m.node_count;
    else if (!f.contours.empty()) f.node_count = f.contours.back().node_count;
    return f;
}

DrapeFeatures drape_features(const cloth::DrapeResult& r, const MeasuredDrape& like)
{
    DrapeFeatures f;
    f.drape_coefficient_percent = r.metrics.drape_coefficient_percent;
    f.hem_min_z = r.hem.min_z;
    if (like.hem_from_side_view) {
        // The side camera (at -y) sees the hem against the pedestal only in
        // front of it: y < 0 and |x| < R2 (x = r cos theta, r ~ the outline's mean radius).
        double zmin = std::numeric_limits<double>::infinity();
        const double c = std::min(1.0, like.disc_diameter / 2 / std::max(r.metrics.mean_radius_m, 1e-6));
        for (std::size_t i = 0; i < r.hem.theta.size(); ++i)
            if (std::sin(r.hem.theta[i]) < 0 && std::abs(std::cos(r.hem.theta[i])) <= c) zmin = std::min(zmin, r.hem.z[i]);
        if (std::isfinite(zmin)) f.hem_min_z = zmin;
    }
    // Slices at the record's depths; a depth the simulation lacks gets an empty
    // (open) profile, whose features say "not closed".
    std::vector<cloth::RadialProfile> profiles;
    std::vector<double> depths;
    for (const auto& c : like.contours) {
        const cloth::Slice* s = nullptr;
        for (const auto& sl : r.slices)
            if (std::abs(sl.depth_m - c.depth_m) < 1e-9) s = &sl;
        profiles.push_back(s ? s->profile : cloth::RadialProfile{});
        depths.push_back(c.depth_m);
    }
    f.contours = stack_features(std::move(profiles), depths, like.recentre_contours, f.axis_offset_m);
    if (like.node_count >= 0) {
        // Counted like the photo: the shadow outline with the photo's detector settings.
        const cloth::DrapeMetrics dm = cloth::drape_metrics(r.outline, like.sample_diameter / 2, like.disc_diameter / 2, like.node_metric_options);
        f.node_count = dm.node_count;
    }
    else if (!f.contours.empty() && f.contours.back().closed) f.node_count = f.contours.back().node_count;
    else f.node_count = r.metrics.node_count;
    return f;
}

} // namespace drape::estimate
