#include "engine/estimate/measured.hpp"

#include "engine/capture/measure.hpp"
#include "engine/core/error.hpp"
#include "engine/core/units.hpp"
#include "engine/record/record.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <numbers>
#include <random>
#include <sstream>

namespace drape::estimate {

namespace fs = std::filesystem;

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
/// A contours file without data: empty, blank, or only its header line. Reads up
/// to its second non-blank line; a file it cannot read, or one larger than the
/// reader takes, is left to record::read_contours to report.
bool no_contour_rows(const std::string& path)
{
    std::error_code ec;
    const auto size = fs::file_size(path, ec);
    if (ec || size > record::kMaxContoursBytes) return false;
    std::ifstream in(path, std::ios::binary);
    if (!in) return false;
    std::string line;
    int lines = 0;
    while (std::getline(in, line)) {
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        if (++lines > 1 || line.find("depth_mm") == std::string::npos) return false;
    }
    return true;
}
} // namespace

MeasuredDrape load_record(const std::string& dir, bool use_photos)
{
    const record::Record rec = record::read_record(dir);
    const std::string meta_path = (rec.dir / "meta.json").string();
    if (rec.specimen.shape != record::Specimen::Shape::Round)
        throw FileError(meta_path + ": field 'configuration.specimen' is not round; the fit simulates round specimens only "
                                    "(drape measure measures other shapes)");
    MeasuredDrape m;
    m.source = dir;
    m.id = rec.specimen_id;
    m.sample_diameter = 2 * rec.R1;
    m.disc_diameter = 2 * rec.R2;
    m.pedestal_height = rec.pedestal_height;
    if (!rec.areal_density)
        throw FileError(meta_path + ": field 'fabric.areal_density_g_m2' is missing (a fit needs the fabric's weight)");
    m.areal_density = *rec.areal_density;
    m.thickness = rec.thickness.value_or(0.5e-3);
    if (rec.lab_drape_coefficient_percent) m.drape_coefficient_percent = *rec.lab_drape_coefficient_percent;
    if (rec.node_count) {
        m.node_count = *rec.node_count;
        m.node_source = "meta.json";
    }
    m.laser_sigma_m = rec.contour_sigma;
    if (const auto it = rec.cameras.find("top"); it != rec.cameras.end()) {
        m.top_camera = it->second;
        std::error_code ec;
        if (const auto photo = rec.file(it->second.image); fs::is_regular_file(photo, ec)) m.top_photo = photo.string();
    }

    // The pedestal the record declares, checked in its side photo: the fit
    // simulates the declared one, so a pedestal that differs is said.
    if (const capture::PedestalWidth pw = capture::measure_pedestal_width(rec); pw.measured) {
        m.pedestal_measured_diameter = pw.diameter;
        m.pedestal_measured_sigma = pw.diameter_sigma;
        if (pw.differs)
            m.notes.push_back("capture: the side photo shows a pedestal " + format_value(pw.diameter * 1e3) + " +- " +
                              format_value(pw.diameter_sigma * 1e3) + " mm across where meta.json declares support_disc_diameter_D2_mm " +
                              format_value(pw.declared * 1e3) + ": the fit simulates the declared one");
    }

    const std::string cpath = rec.file(rec.contours_file).string();
    // Most labs have a camera, not a laser profiler: a record without contours
    // (no file, an empty one, or its header only) is fitted from its photos.
    const bool laser = rec.has_contours() && !no_contour_rows(cpath);
    if (laser) {
        const record::ContourStack stack = record::read_contours(rec);
        for (std::size_t d = 0; d < stack.depths.size(); ++d) {
            // The profiler reports a depth only where the cut closes: every ray has its point.
            if (!stack.profiles[d].complete())
                throw FileError(cpath + ": depth " + format_value(stack.depths[d] * 1e3) + " mm has missing angles (" +
                                std::to_string(stack.points[d].size()) + " of " + std::to_string(stack.profiles[d].size()) + " rays)");
            m.contours.push_back({stack.depths[d], stack.profiles[d]});
        }
        if (m.contours.empty()) throw FileError(cpath + ": no contours");
    } else {
        m.notes.push_back(cpath + ": no laser contours; fitted from the photos (drape coefficient, nodes, hem)");
    }
    // The photos: always without contours, else for the node count when asked to.
    if (!laser || (use_photos && m.node_count < 0)) {
        // The photos: node count from the top view's perspective-corrected
        // outline, lowest hem point from the side view (capture layer).
        try {
            const capture::MeasureOptions mo;
            const capture::Measurement cm = capture::measure_record(rec, mo);
            if (cm.top.measured) {
                if (m.node_count < 0) {
                    m.node_count = cm.top.metrics.node_count;
                    m.node_source = "top photo (capture layer)";
                    m.node_metric_options = mo.metrics;
                }
                m.photo_drape_coefficient_percent = cm.top.metrics.drape_coefficient_percent;
                if (!laser && !std::isfinite(m.drape_coefficient_percent)) {
                    m.drape_coefficient_percent = cm.top.metrics.drape_coefficient_percent;
                    m.notes.push_back("drape coefficient from the top photo (meta.json gives none)");
                }
            }
            if (cm.side.measured && std::isfinite(cm.side.hem_min_z)) {
                m.hem_min_z = cm.side.hem_min_z;
                m.hem_from_side_view = true;
            }
            for (const auto& w : cm.warnings) m.notes.push_back("capture: " + w);
            for (const auto& w : cm.not_measured) m.notes.push_back("capture: not measured: " + w);
        } catch (const drape::Error& e) {
            if (!laser) throw FileError(cpath + ": no laser contours, and the photos could not be measured: " + e.what());
            m.notes.push_back(std::string("capture failed, contours only: ") + e.what());
        }
    }
    if (!laser && !std::isfinite(m.drape_coefficient_percent))
        throw FileError(cpath + ": no laser contours, and neither meta.json (lab_drape_coefficient_percent) nor the top photo gives a "
                                "drape coefficient: nothing to fit the drape to");
    if (m.node_count < 0 && laser) m.node_source = "crests of the deepest contour";
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
    f.cos1_m = f.series.a.empty() ? 0 : f.series.a[0];
    f.sin1_m = f.series.b.empty() ? 0 : f.series.b[0];
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

namespace {
/// Area centroid of a closed cut (nullopt-like: false when it is degenerate).
bool cut_centroid(const cloth::RadialProfile& p, Eigen::Vector2d& centroid)
{
    if (!p.complete()) return false;
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
    if (std::abs(a) < 1e-12) return false;
    centroid = c / (3 * a);
    return true;
}

void move_cut(cloth::RadialProfile& p, const Eigen::Vector2d& shift)
{
    cloth::Polygon2 poly = cloth::polygon_from_profile(p);
    for (auto& v : poly) v -= shift;
    p = cloth::radial_profile(poly, p.size());
}
} // namespace

Eigen::Vector2d recentre_stack(std::vector<cloth::RadialProfile>& profiles)
{
    Eigen::Vector2d tilt;
    return untilt_stack(profiles, {}, tilt);
}

Eigen::Vector2d untilt_stack(std::vector<cloth::RadialProfile>& profiles, const std::vector<double>& depths, Eigen::Vector2d& tilt)
{
    tilt.setZero();
    std::vector<Eigen::Vector2d> cs;
    std::vector<double> ds;
    for (std::size_t i = 0; i < profiles.size(); ++i) {
        Eigen::Vector2d c;
        if (!cut_centroid(profiles[i], c)) continue;
        cs.push_back(c);
        ds.push_back(i < depths.size() ? depths[i] : 0.0);
    }
    if (cs.empty()) return Eigen::Vector2d::Zero();
    const double n = static_cast<double>(cs.size());
    Eigen::Vector2d mc = Eigen::Vector2d::Zero();
    double md = 0;
    for (std::size_t i = 0; i < cs.size(); ++i) {
        mc += cs[i];
        md += ds[i];
    }
    mc /= n; // summed, then divided: re-centring rounds as it did before the tilt
    md /= n;
    double sdd = 0;
    Eigen::Vector2d sdc = Eigen::Vector2d::Zero();
    for (std::size_t i = 0; i < cs.size(); ++i) {
        sdd += (ds[i] - md) * (ds[i] - md);
        sdc += (ds[i] - md) * (cs[i] - mc);
    }
    if (!depths.empty() && sdd > 1e-12) tilt = sdc / sdd;
    const Eigen::Vector2d offset = mc - md * tilt;
    for (std::size_t i = 0; i < profiles.size(); ++i)
        if (profiles[i].complete()) move_cut(profiles[i], offset + (i < depths.size() ? depths[i] : 0.0) * tilt);
    return offset;
}

namespace {
/// Features of a contour stack at the given depths, re-centred when asked.
std::vector<ContourFeatures> stack_features(std::vector<cloth::RadialProfile> profiles, const std::vector<double>& depths,
                                            const MeasuredDrape& how, Eigen::Vector2d& offset, Eigen::Vector2d& tilt)
{
    offset.setZero();
    tilt.setZero();
    if (how.untilt_contours) offset = untilt_stack(profiles, depths, tilt);
    else if (how.recentre_contours) offset = recentre_stack(profiles);
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
    f.contours = stack_features(std::move(profiles), depths, m, f.axis_offset_m, f.axis_tilt);
    if (m.node_count >= 0) f.node_count = m.node_count;
    else if (!f.contours.empty()) f.node_count = f.contours.back().node_count;
    return f;
}

double hem_min_over_arc(const std::vector<double>& theta, const std::vector<double>& z, double a, double b)
{
    if (!(a <= b)) return std::numeric_limits<double>::quiet_NaN();
    // The vertices with a finite angle and height (a diverged solve's are not),
    // in order of angle; equal angles by height, so the order is the same on
    // every run.
    std::vector<std::pair<double, double>> v;
    for (std::size_t i = 0; i < std::min(theta.size(), z.size()); ++i)
        if (std::isfinite(theta[i]) && std::isfinite(z[i])) v.emplace_back(theta[i], z[i]);
    const std::size_t n = v.size();
    if (n == 0) return std::numeric_limits<double>::quiet_NaN();
    std::sort(v.begin(), v.end());
    double zmin = std::numeric_limits<double>::infinity();
    for (const auto& [t, h] : v)
        if (t >= a && t <= b) zmin = std::min(zmin, h);
    // The curve's height at angle t: between the vertices on either side of t
    // (periodic in 2 pi; one vertex is a constant), linearly in angle.
    auto at = [&](double t) {
        const std::size_t pos = static_cast<std::size_t>(
            std::lower_bound(v.begin(), v.end(), t, [](const std::pair<double, double>& p, double x) { return p.first < x; }) - v.begin());
        const std::size_t hi = pos == n ? 0 : pos, lo = pos == 0 ? n - 1 : pos - 1;
        const double t_hi = v[hi].first + (pos == n ? 2 * std::numbers::pi : 0.0), t_lo = v[lo].first - (pos == 0 ? 2 * std::numbers::pi : 0.0);
        if (!(t_hi > t_lo)) return v[hi].second;
        const double w = std::clamp((t - t_lo) / (t_hi - t_lo), 0.0, 1.0);
        return v[lo].second + w * (v[hi].second - v[lo].second);
    };
    return std::min({zmin, at(a), at(b)});
}

DrapeFeatures drape_features(const cloth::DrapeResult& r, const MeasuredDrape& like)
{
    DrapeFeatures f;
    f.drape_coefficient_percent = r.metrics.drape_coefficient_percent;
    f.hem_min_z = r.hem.min_z;
    if (like.hem_from_side_view) {
        // The side camera (at -y) sees the hem against the pedestal only in
        // front of it: y < 0 and |x| < R2 (x = r cos theta, r ~ the outline's mean radius).
        // The arc |cos theta| <= c of the front half is theta in -pi/2 -+ asin(c).
        const double c = std::min(1.0, like.disc_diameter / 2 / std::max(r.metrics.mean_radius_m, 1e-6));
        const double half = std::asin(c);
        const double zmin = hem_min_over_arc(r.hem.theta, r.hem.z, -0.5 * std::numbers::pi - half, -0.5 * std::numbers::pi + half);
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
    f.contours = stack_features(std::move(profiles), depths, like, f.axis_offset_m, f.axis_tilt);
    if (like.node_count >= 0) {
        // Counted like the photo: the shadow outline with the photo's detector settings.
        const cloth::DrapeMetrics dm = cloth::drape_metrics(r.outline, like.sample_diameter / 2, like.disc_diameter / 2, like.node_metric_options);
        f.node_count = dm.node_count;
    }
    else if (!f.contours.empty() && f.contours.back().closed) f.node_count = f.contours.back().node_count;
    else f.node_count = r.metrics.node_count;
    return f;
}

cloth::FabricParams params_for_record(const cloth::FabricParams& base, const MeasuredDrape& m)
{
    cloth::FabricParams p = base;
    p[cloth::Param::AreaDensity] = m.areal_density;
    p[cloth::Param::Thickness] = m.thickness;
    return p;
}

} // namespace drape::estimate
