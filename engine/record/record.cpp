#include "engine/record/record.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/json_reader.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace drape::record {

using nlohmann::json;
namespace fs = std::filesystem;

// ---- Camera -----------------------------------------------------------------

Eigen::Vector2d Camera::project(const Eigen::Vector3d& X) const
{
    const Eigen::Vector3d c = R * X + t;
    if (c.z() <= 0) return {std::nan(""), std::nan("")};
    return {fx * c.x() / c.z() + cx, fy * c.y() / c.z() + cy};
}

Eigen::Vector3d Camera::ray(const Eigen::Vector2d& px) const
{
    const Eigen::Vector3d d((px.x() - cx) / fx, (px.y() - cy) / fy, 1.0);
    return (R.transpose() * d).normalized();
}

std::optional<Eigen::Vector3d> Camera::backproject_to_plane(const Eigen::Vector2d& px, double z) const
{
    const Eigen::Vector3d o = centre(), d = ray(px);
    if (std::abs(d.z()) < 1e-12) return std::nullopt;
    const double s = (z - o.z()) / d.z();
    if (s <= 0) return std::nullopt;
    return o + s * d;
}

bool Camera::has_distortion() const
{
    return std::any_of(dist.begin(), dist.end(), [](double k) { return k != 0.0; });
}

// ---- files inside the record ------------------------------------------------

fs::path Record::file(const std::string& name) const
{
    const std::string where = (dir / "meta.json").string() + ": file name '" + printable(name) + "'";
    if (name.empty()) throw FileError(where + " is empty");
    for (unsigned char c : name)
        if (c < 0x20 || c == 0x7f) throw FileError(where + " contains a control character");
    const fs::path p(name);
    if (p.is_absolute()) throw FileError(where + " is an absolute path; a record names files inside its own folder");
    for (const auto& part : p)
        if (part == "..") throw FileError(where + " climbs out of the record folder with '..'");
    // ".", "./." or "./": the folder itself, whatever links there are.
    if (const fs::path n = p.lexically_normal(); n.empty() || n == "." || n == "./")
        throw FileError(where + " names the record folder itself, not a file in it");
    const fs::path full = dir / p;
    // A symbolic link may still lead out: compare the resolved locations.
    // Fails closed: a name that cannot be resolved (a symbolic-link loop, a
    // folder that cannot be searched) is refused rather than trusted.
    std::error_code ec;
    const fs::path real_dir = fs::weakly_canonical(dir, ec);
    if (ec) throw FileError(where + ": the record folder cannot be resolved (" + ec.message() + ")");
    const fs::path real_file = fs::weakly_canonical(full, ec);
    if (ec) throw FileError(where + " cannot be resolved (" + ec.message() + ")");
    const auto rel = real_file.lexically_relative(real_dir);
    if (rel == "." || (!rel.empty() && rel.lexically_normal() == "."))
        throw FileError(where + " leads (through a symbolic link) to the record folder itself, not a file in it");
    if (rel.empty() || *rel.begin() == "..")
        throw FileError(where + " leads out of the record folder (through a symbolic link) to " + printable(real_file.string()));
    return full;
}

std::string Record::top_image() const
{
    if (top_photo) return top_photo->image;
    if (const auto it = cameras.find("top"); it != cameras.end()) return it->second.image;
    return {};
}

// ---- Specimen -----------------------------------------------------------------

namespace {

/// Outermost crossing of the ray from the origin at angle th with a closed polygon [m]; 0 when none.
double polygon_reach(const std::vector<Eigen::Vector2d>& poly, double th)
{
    const Eigen::Vector2d d(std::cos(th), std::sin(th));
    double best = 0;
    for (std::size_t i = 0; i < poly.size(); ++i) {
        const Eigen::Vector2d a = poly[i], b = poly[(i + 1) % poly.size()];
        const Eigen::Vector2d e = b - a;
        const double den = d.x() * (-e.y()) - d.y() * (-e.x());
        if (std::abs(den) < 1e-15) continue;
        // a + u e = s d  ->  s d - u e = a
        const double s = (a.x() * (-e.y()) - a.y() * (-e.x())) / den;
        const double u = (d.x() * a.y() - d.y() * a.x()) / den;
        if (s > 0 && u >= -1e-12 && u <= 1 + 1e-12) best = std::max(best, s);
    }
    return best;
}

} // namespace

double Specimen::area() const
{
    switch (shape) {
    case Shape::Round: return M_PI * radius * radius;
    case Shape::Rectangle: return width * length;
    case Shape::Polygon: {
        double a = 0;
        for (std::size_t i = 0; i < polygon.size(); ++i) {
            const auto& p = polygon[i];
            const auto& q = polygon[(i + 1) % polygon.size()];
            a += p.x() * q.y() - q.x() * p.y();
        }
        return std::abs(a) / 2;
    }
    }
    return 0;
}

double Specimen::reach(double theta) const
{
    const double t = theta - angle;
    switch (shape) {
    case Shape::Round: return radius;
    case Shape::Rectangle: {
        const double c = std::abs(std::cos(t)), s = std::abs(std::sin(t));
        const double rx = c > 1e-12 ? 0.5 * width / c : std::numeric_limits<double>::infinity();
        const double ry = s > 1e-12 ? 0.5 * length / s : std::numeric_limits<double>::infinity();
        return std::min(rx, ry);
    }
    case Shape::Polygon: return polygon_reach(polygon, t);
    }
    return 0;
}

double Specimen::max_reach() const
{
    double m = 0;
    for (int k = 0; k < 1440; ++k) m = std::max(m, reach(2 * M_PI * k / 1440));
    if (shape == Shape::Rectangle) m = 0.5 * std::hypot(width, length);
    if (shape == Shape::Polygon)
        for (const auto& p : polygon) m = std::max(m, p.norm());
    return m;
}

double Specimen::min_reach() const
{
    double m = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 1440; ++k) m = std::min(m, reach(2 * M_PI * k / 1440));
    return m;
}

double Specimen::equivalent_radius() const { return std::sqrt(area() / M_PI); }

const char* Specimen::shape_name() const
{
    switch (shape) {
    case Shape::Round: return "round";
    case Shape::Rectangle: return "rectangle";
    case Shape::Polygon: return "polygon";
    }
    return "?";
}

std::string Specimen::describe() const
{
    std::ostringstream o;
    o.precision(4);
    switch (shape) {
    case Shape::Round: o << "round, diameter " << 2e3 * radius << " mm"; break;
    case Shape::Rectangle: o << "rectangle " << 1e3 * width << " x " << 1e3 * length << " mm"; break;
    case Shape::Polygon: o << "polygon of " << polygon.size() << " vertices, " << area() * 1e4 << " cm^2"; break;
    }
    if (shape != Shape::Round) {
        if (angle_from_photo) o << ", orientation from the photo";
        else o << " at " << angle * 180 / M_PI << " deg";
    }
    return o.str();
}

const char* to_string(ScaleSource s)
{
    switch (s) {
    case ScaleSource::Calibration: return "calibration";
    case ScaleSource::Disc: return "disc";
    case ScaleSource::Markers: return "markers";
    case ScaleSource::Chessboard: return "chessboard";
    case ScaleSource::PxPerMm: return "px-per-mm";
    }
    return "?";
}

bool Record::has_contours() const
{
    std::error_code ec;
    return fs::is_regular_file(file(contours_file), ec);
}

// ---- meta.json ----------------------------------------------------------------

namespace {

/// Physical ranges of meta.json values (the lab's batch spans far less).
constexpr double kMaxDiameterMm = 2000;   // a drapemeter specimen is 240-360 mm
constexpr double kMaxDensityGm2 = 2000;   // apparel 30-500 g/m^2
constexpr double kMaxThicknessMm = 20;
constexpr double kMaxSigmaMm = 20;
constexpr double kMinThetaStepDeg = 0.01; // 36,000 rays at most
constexpr int kMaxImageSide = 20000;      // px
constexpr double kMaxImagePixels = 150e6; // a 150-megapixel photo: 450 MB decoded (BGR)
constexpr double kMaxFocalPx = 1e6;       // a 20000 px image behind a 50x telephoto
constexpr double kMaxCameraDistanceMm = 1e5; // 100 m
constexpr double kMaxDistortion = 100;    // |k| of OpenCV's rational model; lenses have |k1| < 1
constexpr std::size_t kMaxDepths = 1000;  // contour levels (a profiler stack has tens)
constexpr std::size_t kMaxProfileValues = std::size_t(4) << 20; // depths x rays allocated [values]

Camera read_camera(const JsonReader& m, const json& root, const std::string& name)
{
    const std::string p = "cameras." + name + ".";
    Camera c;
    c.name = name;
    c.image = JsonReader::find(root, p + "image") ? m.string(root, p + "image") : name + ".jpg";
    c.width = m.integer(root, p + "width", 1, kMaxImageSide);
    c.height = m.integer(root, p + "height", 1, kMaxImageSide);
    if (double(c.width) * c.height > kMaxImagePixels)
        m.fail(p + "width", "x height = " + std::to_string(c.width) + " x " + std::to_string(c.height) + " px is more than " +
                                format_value(kMaxImagePixels / 1e6) + " megapixels");
    // The principal point lies near the image; it is allowed one image size out.
    c.fx = m.number_in(root, p + "fx", 1, kMaxFocalPx, "px");
    c.fy = m.number_in(root, p + "fy", 1, kMaxFocalPx, "px");
    c.cx = m.number_in(root, p + "cx", -c.width, 2.0 * c.width, "px");
    c.cy = m.number_in(root, p + "cy", -c.height, 2.0 * c.height, "px");
    if (JsonReader::find(root, p + "dist_coeffs")) c.dist = m.numbers(root, p + "dist_coeffs", 0);
    if (c.dist.size() > 14) m.fail(p + "dist_coeffs", "has " + std::to_string(c.dist.size()) + " entries (OpenCV takes at most 14)");
    for (std::size_t i = 0; i < c.dist.size(); ++i)
        if (std::abs(c.dist[i]) > kMaxDistortion)
            m.fail(p + "dist_coeffs[" + std::to_string(i) + "]", "= " + format_value(c.dist[i]) + " is outside [" +
                                                                    format_value(-kMaxDistortion) + ", " + format_value(kMaxDistortion) + "]");
    const json& Rj = m.need(root, p + "R_world_to_cam");
    if (!Rj.is_array() || Rj.size() != 3) m.fail(p + "R_world_to_cam", "must be a 3x3 array, got " + describe_json(Rj));
    for (int i = 0; i < 3; ++i) {
        const std::string f = p + "R_world_to_cam[" + std::to_string(i) + "]";
        if (!Rj[i].is_array() || Rj[i].size() != 3) m.fail(f, "must be an array of 3 numbers, got " + describe_json(Rj[i]));
        for (int j = 0; j < 3; ++j) {
            if (!Rj[i][j].is_number()) m.fail(f + "[" + std::to_string(j) + "]", "must be a number, got " + describe_json(Rj[i][j]));
            c.R(i, j) = Rj[i][j].get<double>();
        }
    }
    // A rotation must be orthonormal: a typo in a matrix entry would otherwise
    // silently bend every measurement.
    const double orth = (c.R * c.R.transpose() - Eigen::Matrix3d::Identity()).norm();
    if (!std::isfinite(orth) || orth > 1e-3 || c.R.determinant() < 0)
        m.fail(p + "R_world_to_cam", "is not a rotation matrix (|R R^T - I| = " + format_value(orth) + ")");
    const auto t = m.numbers(root, p + "t_world_to_cam_mm", 3);
    for (std::size_t i = 0; i < 3; ++i)
        if (std::abs(t[i]) > kMaxCameraDistanceMm)
            m.fail(p + "t_world_to_cam_mm[" + std::to_string(i) + "]", "= " + format_value(t[i]) + " mm is outside [" +
                                                                          format_value(-kMaxCameraDistanceMm) + ", " +
                                                                          format_value(kMaxCameraDistanceMm) + "] mm");
    c.t = Eigen::Vector3d(t[0], t[1], t[2]) * 1e-3;
    return c;
}

} // namespace

namespace {

Specimen read_specimen(const JsonReader& m, const json& root, std::optional<double> d1_mm)
{
    Specimen sp;
    const json* js = JsonReader::find(root, "configuration.specimen");
    if (!js) {
        if (!d1_mm) m.need(root, "configuration.specimen_diameter_D1_mm"); // names the missing field
        sp.radius = 0.5e-3 * *d1_mm;
        return sp;
    }
    if (!js->is_object()) m.fail("configuration.specimen", "must be an object, got " + describe_json(*js));
    const std::string shape = JsonReader::find(root, "configuration.specimen.shape")
                                  ? m.string(root, "configuration.specimen.shape")
                                  : "round";
    auto angle = [&] {
        const json* a = JsonReader::find(root, "configuration.specimen.angle_deg");
        if (!a) return;
        if (a->is_string() && a->get<std::string>() == "auto") {
            sp.angle_from_photo = true;
            return;
        }
        sp.angle = m.number_in(root, "configuration.specimen.angle_deg", -360, 360, "deg") * M_PI / 180;
    };
    if (shape == "round") {
        sp.radius = 0.5e-3 * m.number_in(root, "configuration.specimen.diameter_mm", 1, kMaxDiameterMm, "mm");
        if (d1_mm && std::abs(*d1_mm - 2e3 * sp.radius) > 1e-6)
            m.fail("configuration.specimen.diameter_mm", "= " + format_value(2e3 * sp.radius) +
                                                             " mm disagrees with specimen_diameter_D1_mm = " + format_value(*d1_mm) + " mm");
    } else if (shape == "rectangle" || shape == "square") {
        const bool square = shape == "square";
        sp.shape = Specimen::Shape::Rectangle;
        sp.width = 1e-3 * m.number_in(root, square ? "configuration.specimen.side_mm" : "configuration.specimen.width_mm", 1,
                                      kMaxDiameterMm, "mm");
        sp.length = square ? sp.width : 1e-3 * m.number_in(root, "configuration.specimen.length_mm", 1, kMaxDiameterMm, "mm");
        angle();
    } else if (shape == "polygon") {
        sp.shape = Specimen::Shape::Polygon;
        const json& pts = m.need(root, "configuration.specimen.points_mm");
        if (!pts.is_array() || pts.size() < 3 || pts.size() > 100000)
            m.fail("configuration.specimen.points_mm", "must be an array of 3 to 100000 [x, y] pairs, got " + describe_json(pts));
        for (std::size_t i = 0; i < pts.size(); ++i) {
            const std::string f = "configuration.specimen.points_mm[" + std::to_string(i) + "]";
            if (!pts[i].is_array() || pts[i].size() != 2 || !pts[i][0].is_number() || !pts[i][1].is_number())
                m.fail(f, "must be [x, y] in mm, got " + describe_json(pts[i]));
            const double x = pts[i][0].get<double>(), y = pts[i][1].get<double>();
            if (!std::isfinite(x) || !std::isfinite(y) || std::hypot(x, y) > kMaxDiameterMm)
                m.fail(f, "lies outside " + format_value(kMaxDiameterMm) + " mm of the disc centre");
            sp.polygon.emplace_back(1e-3 * x, 1e-3 * y);
        }
        angle();
        // The disc centre must be inside: every ray from it crosses the edge.
        for (int k = 0; k < 360; ++k)
            if (!(sp.reach(2 * M_PI * k / 360) > 0))
                m.fail("configuration.specimen.points_mm", "does not enclose the disc centre (0, 0) (no edge at " +
                                                               std::to_string(k) + " deg)");
    } else {
        m.fail("configuration.specimen.shape", "must be \"round\", \"rectangle\", \"square\" or \"polygon\", got \"" + shape + "\"");
    }
    return sp;
}

TopPhoto read_top_photo(const JsonReader& m, const json& root, const Record& rec)
{
    const json& tp = m.need(root, "top_photo");
    if (!tp.is_object()) m.fail("top_photo", "must be an object, got " + describe_json(tp));
    TopPhoto p;
    p.image = m.string(root, "top_photo.image");
    const std::string src = JsonReader::find(root, "top_photo.scale.source") ? m.string(root, "top_photo.scale.source") : "disc";
    if (src == "disc") p.scale = ScaleSource::Disc;
    else if (src == "markers") p.scale = ScaleSource::Markers;
    else if (src == "chessboard") p.scale = ScaleSource::Chessboard;
    else if (src == "px-per-mm" || src == "px_per_mm") p.scale = ScaleSource::PxPerMm;
    else if (src == "calibration") p.scale = ScaleSource::Calibration;
    else
        m.fail("top_photo.scale.source", "must be \"disc\", \"markers\", \"chessboard\", \"px-per-mm\" or \"calibration\", got \"" + src + "\"");
    const double ped_mm = 1e3 * rec.pedestal_height;
    auto opt_len = [&](const std::string& f, double lo, double hi) -> std::optional<double> {
        if (!JsonReader::find(root, f)) return std::nullopt;
        return 1e-3 * m.number_in(root, f, lo, hi, "mm");
    };
    if (auto z = opt_len("top_photo.scale.height_mm", -ped_mm - 1000, 1000)) p.reference_height = *z;
    p.reference_height_sigma = opt_len("top_photo.scale.height_sigma_mm", 0, 500);
    if (p.scale == ScaleSource::PxPerMm) {
        p.px_per_mm = m.number_in(root, "top_photo.scale.px_per_mm", 1e-3, 1e4, "px/mm");
        if (JsonReader::find(root, "top_photo.scale.sigma_percent"))
            p.px_per_mm_sigma_rel = 1e-2 * m.number_in(root, "top_photo.scale.sigma_percent", 0, 50, "%");
    }
    if (p.scale == ScaleSource::Markers) {
        if (JsonReader::find(root, "top_photo.scale.dictionary")) p.marker_dictionary = m.string(root, "top_photo.scale.dictionary");
        p.marker_size = 1e-3 * m.number_in(root, "top_photo.scale.size_mm", 1, 2000, "mm");
        if (const json* lay = JsonReader::find(root, "top_photo.scale.layout_mm")) {
            if (!lay->is_object()) m.fail("top_photo.scale.layout_mm", "must be an object {\"id\": [x, y], ...}, got " + describe_json(*lay));
            for (const auto& [k, v] : lay->items()) {
                const std::string f = "top_photo.scale.layout_mm." + k;
                double idd = 0;
                if (!parse_number(k, idd) || idd < 0 || idd > 10000 || idd != std::floor(idd))
                    m.fail(f, "the key must be a marker id 0..10000");
                if (!v.is_array() || v.size() != 2 || !v[0].is_number() || !v[1].is_number() ||
                    !std::isfinite(v[0].get<double>()) || !std::isfinite(v[1].get<double>()) ||
                    std::abs(v[0].get<double>()) > 1e4 || std::abs(v[1].get<double>()) > 1e4)
                    m.fail(f, "must be the marker centre [x, y] in mm on the sheet, got " + describe_json(v));
                p.marker_layout[static_cast<int>(idd)] = Eigen::Vector2d(v[0].get<double>(), v[1].get<double>()) * 1e-3;
            }
        }
    }
    if (p.scale == ScaleSource::Chessboard) {
        const auto ic = m.numbers(root, "top_photo.scale.inner_corners", 2);
        for (double v : ic)
            if (v < 2 || v > 100 || v != std::floor(v)) m.fail("top_photo.scale.inner_corners", "must be two whole numbers 2..100");
        p.board_cols = static_cast<int>(ic[0]);
        p.board_rows = static_cast<int>(ic[1]);
        p.board_square = 1e-3 * m.number_in(root, "top_photo.scale.square_mm", 1, 1000, "mm");
    }
    if (p.scale == ScaleSource::Calibration && !rec.has_camera("top"))
        m.fail("top_photo.scale.source", "is \"calibration\" but there is no 'cameras.top'");
    if (JsonReader::find(root, "top_photo.disc_px")) {
        const auto c = m.numbers(root, "top_photo.disc_px.centre", 2);
        p.disc_centre_px = Eigen::Vector2d(c[0], c[1]);
        if (JsonReader::find(root, "top_photo.disc_px.radius"))
            p.disc_radius_px = m.number_in(root, "top_photo.disc_px.radius", 2, kMaxImageSide, "px");
    }
    if (auto e = opt_len("top_photo.disc_edge_sigma_mm", 0, 50)) p.disc_edge_sigma = *e;
    p.camera_height = opt_len("top_photo.camera_height_mm", 50, 20000);
    p.camera_height_sigma = opt_len("top_photo.camera_height_sigma_mm", 0, 10000);
    if (JsonReader::find(root, "top_photo.focal_px")) p.focal_px = m.number_in(root, "top_photo.focal_px", 10, 1e6, "px");
    if (JsonReader::find(root, "top_photo.perspective")) {
        p.perspective = m.string(root, "top_photo.perspective");
        if (p.perspective != "none" && p.perspective != "disc-plane" && p.perspective != "hem" && p.perspective != "auto")
            m.fail("top_photo.perspective", "must be \"none\", \"disc-plane\", \"hem\" or \"auto\", got \"" + p.perspective + "\"");
    }
    if (JsonReader::find(root, "top_photo.mask")) p.mask = m.string(root, "top_photo.mask");
    if (JsonReader::find(root, "top_photo.threshold")) p.threshold = m.string(root, "top_photo.threshold");
    rec.file(p.image); // a photo outside the record is refused here
    if (!p.mask.empty()) rec.file(p.mask);
    return p;
}

} // namespace

Record parse_meta(const std::string& text, const fs::path& dir, const std::string& where)
{
    const json root = parse_json(text, where);
    return parse_meta_json(root, dir, where);
}

Record parse_meta_json(const json& root, const fs::path& dir, const std::string& where)
{
    if (!root.is_object()) throw FileError(where + ": top level must be a JSON object, got " + describe_json(root));
    const JsonReader m(where);
    Record rec;
    rec.dir = dir;
    rec.raw = root;
    // A folder name need not be UTF-8; the id goes into JSON outputs.
    rec.specimen_id = JsonReader::find(root, "specimen_id") ? m.string(root, "specimen_id") : printable(dir.filename().string(), 200);

    // Lengths in meta.json are mm (README "World frame and units").
    std::optional<double> d1_mm;
    if (JsonReader::find(root, "configuration.specimen_diameter_D1_mm") || !JsonReader::find(root, "configuration.specimen"))
        d1_mm = m.number_in(root, "configuration.specimen_diameter_D1_mm", 1, kMaxDiameterMm, "mm");
    rec.specimen = read_specimen(m, root, d1_mm);
    rec.R1 = rec.specimen.shape == Specimen::Shape::Round ? rec.specimen.radius : rec.specimen.equivalent_radius();
    rec.R2 = 0.5e-3 * m.number_in(root, "configuration.support_disc_diameter_D2_mm", 1, kMaxDiameterMm, "mm");
    if (rec.R2 >= rec.specimen.min_reach())
        m.fail("configuration.support_disc_diameter_D2_mm",
               "= " + format_value(2e3 * rec.R2) + " mm: the specimen (" + rec.specimen.describe() +
                   ") must cover the disc (its nearest edge is " + format_value(1e3 * rec.specimen.min_reach()) +
                   " mm from the centre)");
    if (JsonReader::find(root, "configuration.pedestal_height_mm"))
        rec.pedestal_height = 1e-3 * m.number_in(root, "configuration.pedestal_height_mm", 1, 5000, "mm");
    if (JsonReader::find(root, "fabric.areal_density_g_m2"))
        rec.areal_density = 1e-3 * m.number_in(root, "fabric.areal_density_g_m2", 1, kMaxDensityGm2, "g/m^2");
    if (JsonReader::find(root, "fabric.thickness_mm"))
        rec.thickness = 1e-3 * m.number_in(root, "fabric.thickness_mm", 0.001, kMaxThicknessMm, "mm");
    if (JsonReader::find(root, "fabric.colour")) rec.colour = m.string(root, "fabric.colour");
    if (JsonReader::find(root, "units.length")) {
        const std::string u = m.string(root, "units.length");
        if (u != "mm") m.fail("units.length", "must be \"mm\" (the format's unit), got \"" + u + "\"");
    }

    if (const json* cams = JsonReader::find(root, "cameras")) {
        if (!cams->is_object()) m.fail("cameras", "must be an object, got " + describe_json(*cams));
        for (const auto& [name, v] : cams->items()) {
            (void)v;
            rec.cameras[name] = read_camera(m, root, name);
        }
    }
    if (const json* boards = JsonReader::find(root, "calibration_boards")) {
        if (!boards->is_array()) m.fail("calibration_boards", "must be an array, got " + describe_json(*boards));
        for (std::size_t i = 0; i < boards->size(); ++i) {
            json wrap = {{"b", (*boards)[i]}};
            const JsonReader bm(where + " calibration_boards[" + std::to_string(i) + "]");
            Board b;
            b.name = JsonReader::find(wrap, "b.name") ? bm.string(wrap, "b.name") : std::to_string(i);
            b.x0 = 1e-3 * bm.number_in(wrap, "b.x0_mm", -1e4, 1e4, "mm");
            b.y0 = 1e-3 * bm.number_in(wrap, "b.y0_mm", -1e4, 1e4, "mm");
            b.nx = bm.integer(wrap, "b.nx", 3, 200);
            b.ny = bm.integer(wrap, "b.ny", 3, 200);
            b.square = 1e-3 * (JsonReader::find(wrap, "b.square_mm") ? bm.number_in(wrap, "b.square_mm", 1, 500, "mm") : 25.0);
            b.z = 1e-3 * (JsonReader::find(wrap, "b.z_mm") ? bm.number_in(wrap, "b.z_mm", -1e4, 1e4, "mm") : -1e3 * rec.pedestal_height);
            rec.boards.push_back(b);
        }
    }
    if (JsonReader::find(root, "contours")) {
        if (JsonReader::find(root, "contours.file")) rec.contours_file = m.string(root, "contours.file");
        if (JsonReader::find(root, "contours.depths_mm")) {
            const auto depths = m.numbers(root, "contours.depths_mm", 0);
            if (depths.size() > kMaxDepths)
                m.fail("contours.depths_mm", "holds " + std::to_string(depths.size()) + " depths, more than " + std::to_string(kMaxDepths));
            for (double d : depths) {
                if (!(d > 0) || d > 1e3 * rec.pedestal_height)
                    m.fail("contours.depths_mm", "holds " + format_value(d) + " mm, outside (0, " +
                                                     format_value(1e3 * rec.pedestal_height) + "] mm (the pedestal height)");
                rec.contour_depths.push_back(d * 1e-3);
            }
        }
        if (JsonReader::find(root, "contours.theta_step_deg")) {
            const double step = m.number_in(root, "contours.theta_step_deg", kMinThetaStepDeg, 45, "deg");
            if (std::abs(360.0 / step - std::round(360.0 / step)) > 1e-6)
                m.fail("contours.theta_step_deg", "= " + format_value(step) + " deg does not divide 360 deg");
            rec.contour_theta_step_deg = step;
        }
        if (JsonReader::find(root, "contours.repeatability_sigma_mm"))
            rec.contour_sigma = 1e-3 * m.number_in(root, "contours.repeatability_sigma_mm", 1e-4, kMaxSigmaMm, "mm");
    }
    if (JsonReader::find(root, "lab_drape_coefficient_percent"))
        rec.lab_drape_coefficient_percent = m.number_in(root, "lab_drape_coefficient_percent", 0, 100, "%");
    if (JsonReader::find(root, "node_count")) rec.node_count = m.integer(root, "node_count", 0, 60);
    if (JsonReader::find(root, "top_photo")) rec.top_photo = read_top_photo(m, root, rec);

    static const std::set<std::string> known = {
        "specimen_id", "configuration", "fabric", "gravity_m_s2", "units", "world_frame", "cameras",
        "camera_model", "calibration_boards", "contours", "lab_drape_coefficient_percent", "node_count", "top_photo"};
    for (const auto& [k, v] : root.items()) {
        (void)v;
        if (!known.count(k)) rec.unknown_fields.push_back(k);
    }
    return rec;
}

Record read_record(const fs::path& dir)
{
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) throw FileError(dir.string() + ": not a record folder");
    const auto meta = dir / "meta.json";
    if (!fs::exists(meta, ec)) throw FileError(meta.string() + ": cannot be read (every record needs meta.json)");
    return parse_meta(read_file(meta.string(), std::size_t(4) << 20), dir, meta.string());
}

// ---- contours.csv -------------------------------------------------------------

namespace {

std::vector<std::string> split_csv(const std::string& line)
{
    std::vector<std::string> out;
    std::string cell;
    std::stringstream ss(line);
    while (std::getline(ss, cell, ',')) {
        while (!cell.empty() && (cell.back() == '\r' || cell.back() == ' ')) cell.pop_back();
        while (!cell.empty() && cell.front() == ' ') cell.erase(cell.begin());
        out.push_back(cell);
    }
    if (!line.empty() && line.back() == ',') out.emplace_back();
    return out;
}

struct Row {
    double depth, theta, x, y;
    int line;
};

} // namespace

ContourStack read_contours_file(const fs::path& file, double theta_step_deg, double R1, double R2, double pedestal_height)
{
    const std::string path = file.string();
    return parse_contours(read_file(path, kMaxContoursBytes), path, theta_step_deg, R1, R2, pedestal_height);
}

ContourStack parse_contours(const std::string& text, const std::string& path, double theta_step_deg, double R1, double R2,
                            double pedestal_height)
{
    std::istringstream in(text);
    std::string line;
    if (!std::getline(in, line)) throw FileError(path + ": empty file (expected a header line depth_mm,theta_deg,x_mm,y_mm)");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto header = split_csv(line);
    auto column = [&](const std::string& name) {
        for (std::size_t i = 0; i < header.size(); ++i)
            if (header[i] == name) return static_cast<int>(i);
        throw FileError(path + ": missing column '" + name + "' in header '" + printable(line) + "'");
    };
    const int c_depth = column("depth_mm"), c_theta = column("theta_deg"), c_x = column("x_mm"), c_y = column("y_mm");

    // Bounds of a physical drape: below the pedestal top and above the floor;
    // outside half the disc radius (the cloth hangs outside the pedestal) and
    // within kMaxContourReach specimen radii of the axis (a specimen off centre
    // by a fifth of its radius is still read; 1e308 mm or a 40 % larger radius
    // is not).
    const double depth_max_mm = 1e3 * pedestal_height, r_min_mm = 0.5e3 * R2, r_max_mm = kMaxContourReach * 1e3 * R1;
    std::vector<Row> rows;
    int line_no = 1;
    while (std::getline(in, line)) {
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (line.empty()) continue;
        const auto cells = split_csv(line);
        auto num = [&](int c, const char* name) {
            const std::string where = path + ":" + std::to_string(line_no) + ": column '" + name + "'";
            if (c >= static_cast<int>(cells.size())) throw FileError(where + " is missing in '" + printable(line) + "'");
            double v = 0;
            if (!parse_number(cells[static_cast<std::size_t>(c)], v))
                throw FileError(where + ": '" + printable(cells[static_cast<std::size_t>(c)]) + "' is not a number");
            return v;
        };
        Row r{num(c_depth, "depth_mm"), num(c_theta, "theta_deg"), num(c_x, "x_mm"), num(c_y, "y_mm"), line_no};
        const std::string where = path + ":" + std::to_string(line_no) + ": ";
        if (!(r.depth > 0) || r.depth > depth_max_mm)
            throw FileError(where + "depth_mm = " + format_value(r.depth) + " is outside (0, " + format_value(depth_max_mm) +
                            "] mm (below the pedestal top, above the floor)");
        if (r.theta < 0 || r.theta >= 360)
            throw FileError(where + "theta_deg = " + format_value(r.theta) + " is outside [0, 360) deg");
        const double rr = std::hypot(r.x, r.y);
        if (!(rr >= r_min_mm) || rr > r_max_mm)
            throw FileError(where + "x_mm, y_mm: the point (" + format_value(r.x) + ", " + format_value(r.y) + ") mm lies " +
                            format_value(rr) + " mm from the axis, outside [" + format_value(r_min_mm) + ", " + format_value(r_max_mm) +
                            "] mm (half the disc radius .. " + format_value(kMaxContourReach) + " specimen radii)");
        rows.push_back(r);
        if (rows.size() > kMaxProfileValues)
            throw FileError(path + ": more than " + std::to_string(kMaxProfileValues) + " rows (more rays than this reader allocates)");
    }
    if (rows.empty()) throw FileError(path + ": no data rows");

    // The ray spacing: declared, else the smallest gap between the angles.
    double step = theta_step_deg;
    if (!(step > 0)) {
        std::vector<double> th;
        for (const auto& r : rows) th.push_back(r.theta);
        std::sort(th.begin(), th.end());
        th.erase(std::unique(th.begin(), th.end(), [](double a, double b) { return std::abs(a - b) < 1e-6; }), th.end());
        step = 360.0;
        for (std::size_t i = 1; i < th.size(); ++i) step = std::min(step, th[i] - th[i - 1]);
        if (th.size() == 1) step = 1.0;
    }
    const double nd = 360.0 / step;
    if (!(step >= kMinThetaStepDeg) || std::abs(nd - std::round(nd)) > 1e-3)
        throw FileError(path + ": the angles are not on a regular grid that divides 360 deg (step " + format_value(step) + " deg)");
    const int n = static_cast<int>(std::lround(nd));
    if (n < 8) throw FileError(path + ": angular step " + format_value(step) + " deg is too coarse (fewer than 8 rays)");

    ContourStack st;
    std::map<double, std::size_t> index; // depth [mm] -> slot
    for (const auto& r : rows) index.emplace(r.depth, 0);
    // Sizes before allocation: one profile of n rays per depth.
    if (index.size() > kMaxDepths)
        throw FileError(path + ": " + std::to_string(index.size()) + " different depths, more than the " + std::to_string(kMaxDepths) +
                        " contour levels this reader takes");
    if (index.size() * static_cast<std::size_t>(n) > kMaxProfileValues)
        throw FileError(path + ": " + std::to_string(index.size()) + " depths x " + std::to_string(n) + " rays (step " +
                        format_value(step) + " deg) = " + std::to_string(index.size() * static_cast<std::size_t>(n)) +
                        " profile values, more than the " + std::to_string(kMaxProfileValues) + " this reader allocates");
    for (auto& [d, slot] : index) {
        slot = st.depths.size();
        st.depths.push_back(d * 1e-3);
        st.profiles.push_back({std::vector<double>(static_cast<std::size_t>(n), std::numeric_limits<double>::quiet_NaN())});
        st.points.emplace_back();
    }
    for (const auto& r : rows) {
        const std::size_t s = index.at(r.depth);
        const double kk = r.theta / step;
        const int k = static_cast<int>(std::lround(kk));
        if (std::abs(kk - k) > 1e-3 || k >= n)
            throw FileError(path + ":" + std::to_string(r.line) + ": theta_deg = " + format_value(r.theta) +
                            " is not on the regular " + format_value(step) + " degree grid");
        double& slot = st.profiles[s].r[static_cast<std::size_t>(k)];
        if (!std::isnan(slot))
            throw FileError(path + ":" + std::to_string(r.line) + ": depth " + format_value(r.depth) + " mm, theta_deg = " +
                            format_value(r.theta) + " appears twice");
        slot = std::hypot(r.x, r.y) * 1e-3;
        st.points[s].emplace_back(r.x * 1e-3, r.y * 1e-3);
    }
    return st;
}

bool no_contour_rows(const fs::path& file)
{
    std::error_code ec;
    const auto size = fs::file_size(file, ec);
    if (ec || size > kMaxContoursBytes) return false;
    std::ifstream in(file, std::ios::binary);
    if (!in) return false;
    std::string line;
    int lines = 0;
    while (std::getline(in, line)) {
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        if (++lines > 1 || line.find("depth_mm") == std::string::npos) return false;
    }
    return true;
}

ContourStack read_contours(const Record& rec)
{
    return read_contours_file(rec.file(rec.contours_file), rec.contour_theta_step_deg.value_or(0.0),
                              std::max(rec.R1, rec.specimen.max_reach()), rec.R2, rec.pedestal_height);
}

} // namespace drape::record
