#include "engine/record/record.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/json_reader.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#include <Eigen/LU>

#include <algorithm>
#include <cmath>
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
    if (rel.empty() || *rel.begin() == ".." || rel == ".")
        throw FileError(where + " leads out of the record folder (through a symbolic link) to " + printable(real_file.string()));
    return full;
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

Record parse_meta(const std::string& text, const fs::path& dir, const std::string& where)
{
    const json root = parse_json(text, where);
    if (!root.is_object()) throw FileError(where + ": top level must be a JSON object, got " + describe_json(root));
    const JsonReader m(where);
    Record rec;
    rec.dir = dir;
    rec.raw = root;
    // A folder name need not be UTF-8; the id goes into JSON outputs.
    rec.specimen_id = JsonReader::find(root, "specimen_id") ? m.string(root, "specimen_id") : printable(dir.filename().string(), 200);

    // Lengths in meta.json are mm (README "World frame and units").
    rec.R1 = 0.5e-3 * m.number_in(root, "configuration.specimen_diameter_D1_mm", 1, kMaxDiameterMm, "mm");
    rec.R2 = 0.5e-3 * m.number_in(root, "configuration.support_disc_diameter_D2_mm", 1, kMaxDiameterMm, "mm");
    if (rec.R2 >= rec.R1)
        m.fail("configuration.support_disc_diameter_D2_mm", "= " + format_value(2e3 * rec.R2) +
                                                                " mm must be smaller than specimen_diameter_D1_mm = " +
                                                                format_value(2e3 * rec.R1) + " mm");
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

    static const std::set<std::string> known = {
        "specimen_id", "configuration", "fabric", "gravity_m_s2", "units", "world_frame", "cameras",
        "camera_model", "calibration_boards", "contours", "lab_drape_coefficient_percent", "node_count"};
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
    // within 1.5 specimen radii of the axis (a specimen off centre by a third
    // of its radius is still read; 1e308 is not).
    const double depth_max_mm = 1e3 * pedestal_height, r_min_mm = 0.5e3 * R2, r_max_mm = 1.5e3 * R1;
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
            throw FileError(where + "the point (" + format_value(r.x) + ", " + format_value(r.y) + ") mm lies " + format_value(rr) +
                            " mm from the axis, outside [" + format_value(r_min_mm) + ", " + format_value(r_max_mm) +
                            "] mm (half the disc radius .. 1.5 specimen radii)");
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

ContourStack read_contours(const Record& rec)
{
    return read_contours_file(rec.file(rec.contours_file), rec.contour_theta_step_deg.value_or(0.0), rec.R1, rec.R2,
                              rec.pedestal_height);
}

} // namespace drape::record
