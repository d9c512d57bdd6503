#include "engine/capture/record.hpp"

#include "engine/cloth/error.hpp"

#include <Eigen/LU>
#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>

namespace drape::capture {

using nlohmann::json;

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
    for (double k : dist)
        if (k != 0.0) return true;
    return false;
}

// ---- meta.json ----------------------------------------------------------------

namespace {

std::string describe(const json& v)
{
    std::string s = v.dump();
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return std::string(v.type_name()) + " " + s;
}

class MetaReader {
public:
    explicit MetaReader(std::string where) : m_where(std::move(where)) {}

    [[noreturn]] void fail(const std::string& field, const std::string& what) const
    {
        throw FileError(m_where + ": field '" + field + "' " + what);
    }

    const json* find(const json& root, const std::string& path) const
    {
        const json* cur = &root;
        std::stringstream ss(path);
        std::string key;
        while (std::getline(ss, key, '.')) {
            if (!cur->is_object()) return nullptr;
            auto it = cur->find(key);
            if (it == cur->end()) return nullptr;
            cur = &*it;
        }
        return cur;
    }

    const json& need(const json& root, const std::string& path) const
    {
        const json* v = find(root, path);
        if (!v) fail(path, "is missing");
        return *v;
    }

    double number(const json& root, const std::string& path) const
    {
        const json& v = need(root, path);
        if (!v.is_number()) fail(path, "must be a number, got " + describe(v));
        const double d = v.get<double>();
        if (!std::isfinite(d)) fail(path, "must be finite, got " + describe(v));
        return d;
    }

    double positive(const json& root, const std::string& path) const
    {
        const double d = number(root, path);
        if (!(d > 0)) fail(path, "must be > 0, got " + describe(need(root, path)));
        return d;
    }

    std::optional<double> optional_number(const json& root, const std::string& path) const
    {
        if (!find(root, path)) return std::nullopt;
        return number(root, path);
    }

    int integer(const json& root, const std::string& path, int min) const
    {
        const json& v = need(root, path);
        if (!v.is_number_integer() && !(v.is_number() && std::floor(v.get<double>()) == v.get<double>()))
            fail(path, "must be an integer, got " + describe(v));
        const double d = v.get<double>();
        if (d < min || d > 1e6) fail(path, "must be an integer >= " + std::to_string(min) + ", got " + describe(v));
        return static_cast<int>(d);
    }

    std::string string(const json& root, const std::string& path) const
    {
        const json& v = need(root, path);
        if (!v.is_string()) fail(path, "must be a string, got " + describe(v));
        return v.get<std::string>();
    }

    std::vector<double> numbers(const json& root, const std::string& path, std::size_t n_expected) const
    {
        const json& v = need(root, path);
        if (!v.is_array()) fail(path, "must be an array of numbers, got " + describe(v));
        if (n_expected && v.size() != n_expected)
            fail(path, "must have " + std::to_string(n_expected) + " entries, got " + std::to_string(v.size()));
        std::vector<double> out;
        for (std::size_t i = 0; i < v.size(); ++i) {
            if (!v[i].is_number())
                fail(path + "[" + std::to_string(i) + "]", "must be a number, got " + describe(v[i]));
            out.push_back(v[i].get<double>());
        }
        return out;
    }

    const std::string& where() const { return m_where; }

private:
    std::string m_where;
};

Camera read_camera(const MetaReader& m, const json& root, const std::string& name)
{
    const std::string p = "cameras." + name + ".";
    Camera c;
    c.name = name;
    c.image = m.find(root, p + "image") ? m.string(root, p + "image") : name + ".jpg";
    c.width = m.integer(root, p + "width", 1);
    c.height = m.integer(root, p + "height", 1);
    c.fx = m.positive(root, p + "fx");
    c.fy = m.positive(root, p + "fy");
    c.cx = m.number(root, p + "cx");
    c.cy = m.number(root, p + "cy");
    if (m.find(root, p + "dist_coeffs")) c.dist = m.numbers(root, p + "dist_coeffs", 0);
    const json& Rj = m.need(root, p + "R_world_to_cam");
    if (!Rj.is_array() || Rj.size() != 3) m.fail(p + "R_world_to_cam", "must be a 3x3 array, got " + describe(Rj));
    for (int i = 0; i < 3; ++i) {
        const std::string f = p + "R_world_to_cam[" + std::to_string(i) + "]";
        if (!Rj[i].is_array() || Rj[i].size() != 3) m.fail(f, "must be an array of 3 numbers, got " + describe(Rj[i]));
        for (int j = 0; j < 3; ++j) {
            if (!Rj[i][j].is_number()) m.fail(f + "[" + std::to_string(j) + "]", "must be a number, got " + describe(Rj[i][j]));
            c.R(i, j) = Rj[i][j].get<double>();
        }
    }
    // A rotation must be orthonormal: a typo in a matrix entry would otherwise
    // silently bend every measurement.
    const double orth = (c.R * c.R.transpose() - Eigen::Matrix3d::Identity()).norm();
    if (orth > 1e-3 || c.R.determinant() < 0)
        m.fail(p + "R_world_to_cam", "is not a rotation matrix (|R R^T - I| = " + std::to_string(orth) + ")");
    const auto t = m.numbers(root, p + "t_world_to_cam_mm", 3);
    c.t = Eigen::Vector3d(t[0], t[1], t[2]) * 1e-3;
    return c;
}

} // namespace

Record parse_meta(const std::string& text, const std::filesystem::path& dir, const std::string& where)
{
    json root;
    try {
        root = json::parse(text);
    } catch (const json::parse_error& e) {
        throw FileError(where + ": not valid JSON (" + std::string(e.what()) + ")");
    }
    if (!root.is_object()) throw FileError(where + ": top level must be a JSON object, got " + describe(root));
    MetaReader m(where);
    Record rec;
    rec.dir = dir;
    rec.raw = root;
    rec.specimen_id = m.find(root, "specimen_id") ? m.string(root, "specimen_id") : dir.filename().string();

    // Lengths in meta.json are mm (README "World frame and units").
    rec.R1 = 0.5e-3 * m.positive(root, "configuration.specimen_diameter_D1_mm");
    rec.R2 = 0.5e-3 * m.positive(root, "configuration.support_disc_diameter_D2_mm");
    if (rec.R2 >= rec.R1)
        m.fail("configuration.support_disc_diameter_D2_mm", "must be smaller than specimen_diameter_D1_mm");
    rec.pedestal_height = m.find(root, "configuration.pedestal_height_mm")
                              ? 1e-3 * m.positive(root, "configuration.pedestal_height_mm")
                              : 0.120;
    if (auto w = m.optional_number(root, "fabric.areal_density_g_m2")) rec.areal_density = *w * 1e-3;
    if (auto th = m.optional_number(root, "fabric.thickness_mm")) rec.thickness = *th * 1e-3;
    if (m.find(root, "fabric.colour")) rec.colour = m.string(root, "fabric.colour");
    if (m.find(root, "units.length")) {
        const std::string u = m.string(root, "units.length");
        if (u != "mm") m.fail("units.length", "must be \"mm\" (the format's unit), got \"" + u + "\"");
    }

    if (const json* cams = m.find(root, "cameras")) {
        if (!cams->is_object()) m.fail("cameras", "must be an object, got " + describe(*cams));
        for (const auto& [name, v] : cams->items()) {
            (void)v;
            rec.cameras[name] = read_camera(m, root, name);
        }
    }
    if (const json* boards = m.find(root, "calibration_boards")) {
        if (!boards->is_array()) m.fail("calibration_boards", "must be an array, got " + describe(*boards));
        for (std::size_t i = 0; i < boards->size(); ++i) {
            json wrap = {{"b", (*boards)[i]}};
            MetaReader bm(where + " calibration_boards[" + std::to_string(i) + "]");
            Board b;
            b.name = bm.find(wrap, "b.name") ? bm.string(wrap, "b.name") : std::to_string(i);
            b.x0 = 1e-3 * bm.number(wrap, "b.x0_mm");
            b.y0 = 1e-3 * bm.number(wrap, "b.y0_mm");
            b.nx = bm.integer(wrap, "b.nx", 3);
            b.ny = bm.integer(wrap, "b.ny", 3);
            b.square = 1e-3 * (bm.find(wrap, "b.square_mm") ? bm.positive(wrap, "b.square_mm") : 25.0);
            b.z = 1e-3 * (bm.find(wrap, "b.z_mm") ? bm.number(wrap, "b.z_mm") : -1e3 * rec.pedestal_height);
            rec.boards.push_back(b);
        }
    }
    if (m.find(root, "contours")) {
        if (m.find(root, "contours.file")) rec.contours_file = m.string(root, "contours.file");
        if (m.find(root, "contours.depths_mm"))
            for (double d : m.numbers(root, "contours.depths_mm", 0)) rec.contour_depths.push_back(d * 1e-3);
        if (m.find(root, "contours.theta_step_deg")) rec.contour_theta_step_deg = m.positive(root, "contours.theta_step_deg");
        if (m.find(root, "contours.repeatability_sigma_mm"))
            rec.contour_sigma = 1e-3 * m.positive(root, "contours.repeatability_sigma_mm");
    }
    rec.lab_drape_coefficient_percent = m.optional_number(root, "lab_drape_coefficient_percent");

    static const std::set<std::string> known = {
        "specimen_id", "configuration", "fabric", "gravity_m_s2", "units", "world_frame", "cameras",
        "camera_model", "calibration_boards", "contours", "lab_drape_coefficient_percent"};
    for (const auto& [k, v] : root.items()) {
        (void)v;
        if (!known.count(k)) rec.unknown_fields.push_back(k);
    }
    return rec;
}

Record read_record(const std::filesystem::path& dir)
{
    if (!std::filesystem::is_directory(dir)) throw FileError(dir.string() + ": not a record directory");
    const auto meta = dir / "meta.json";
    std::ifstream in(meta, std::ios::binary);
    if (!in) throw FileError(meta.string() + ": cannot be read (every record needs meta.json)");
    std::stringstream ss;
    ss << in.rdbuf();
    return parse_meta(ss.str(), dir, meta.string());
}

// ---- images -------------------------------------------------------------------

cv::Mat load_image(const Record& rec, const std::string& camera)
{
    auto it = rec.cameras.find(camera);
    if (it == rec.cameras.end())
        throw FileError(rec.dir.string() + "/meta.json: field 'cameras." + camera + "' is missing");
    const Camera& cam = it->second;
    const auto path = rec.file(cam.image);
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path.string() + ": cannot be read");
    std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (bytes.empty()) throw FileError(path.string() + ": empty file");
    // libjpeg decodes a truncated file with a grey bottom and only a warning;
    // a JPEG must end with the EOI marker FF D9 (trailing padding allowed).
    const bool is_jpeg = bytes.size() > 3 && bytes[0] == 0xFF && bytes[1] == 0xD8;
    if (is_jpeg) {
        std::size_t end = bytes.size();
        while (end > 2 && bytes[end - 1] == 0x00) --end;
        if (!(bytes[end - 2] == 0xFF && bytes[end - 1] == 0xD9))
            throw FileError(path.string() + ": truncated JPEG (no end-of-image marker after " +
                            std::to_string(bytes.size()) + " bytes)");
    }
    cv::Mat img = cv::imdecode(bytes, cv::IMREAD_COLOR);
    if (img.empty()) throw FileError(path.string() + ": not a readable image");
    if (img.cols != cam.width || img.rows != cam.height)
        throw FileError(path.string() + ": image is " + std::to_string(img.cols) + " x " + std::to_string(img.rows) +
                        " px but meta.json field 'cameras." + camera + ".width/height' declares " +
                        std::to_string(cam.width) + " x " + std::to_string(cam.height));
    return img;
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

} // namespace

ContourStack read_contours_file(const std::filesystem::path& file, double theta_step_deg)
{
    std::ifstream in(file);
    if (!in) throw FileError(file.string() + ": cannot be read");
    std::string line;
    if (!std::getline(in, line)) throw FileError(file.string() + ": empty file (expected a header line)");
    const auto header = split_csv(line);
    auto column = [&](const std::string& name) {
        for (std::size_t i = 0; i < header.size(); ++i)
            if (header[i] == name) return static_cast<int>(i);
        throw FileError(file.string() + ": missing column '" + name + "' in header '" + line + "'");
    };
    const int c_depth = column("depth_mm"), c_theta = column("theta_deg"), c_x = column("x_mm"), c_y = column("y_mm");
    const int n = static_cast<int>(std::lround(360.0 / theta_step_deg));
    if (n < 8) throw FileError(file.string() + ": angular step " + std::to_string(theta_step_deg) + " deg is too coarse");

    ContourStack st;
    std::map<double, std::size_t> index; // depth [mm] -> slot
    int line_no = 1;
    while (std::getline(in, line)) {
        ++line_no;
        if (line.empty() || line == "\r") continue;
        const auto cells = split_csv(line);
        auto num = [&](int c, const char* name) {
            const std::string where = file.string() + ":" + std::to_string(line_no) + ": column '" + name + "'";
            if (c >= static_cast<int>(cells.size())) throw FileError(where + " is missing in '" + line + "'");
            std::size_t pos = 0;
            double v = 0;
            try {
                v = std::stod(cells[c], &pos);
            } catch (const std::exception&) {
                pos = 0;
            }
            if (pos == 0 || pos != cells[c].size() || !std::isfinite(v))
                throw FileError(where + ": '" + cells[c] + "' is not a number");
            return v;
        };
        const double d = num(c_depth, "depth_mm"), th = num(c_theta, "theta_deg");
        const double x = num(c_x, "x_mm"), y = num(c_y, "y_mm");
        auto [it, added] = index.emplace(d, st.depths.size());
        if (added) {
            st.depths.push_back(d * 1e-3);
            st.profiles.push_back({std::vector<double>(n, std::numeric_limits<double>::quiet_NaN())});
            st.points.emplace_back();
        }
        const std::size_t s = it->second;
        const int k = static_cast<int>(std::lround(th / theta_step_deg)) % n;
        st.profiles[s].r[(k + n) % n] = std::hypot(x, y) * 1e-3;
        st.points[s].emplace_back(x * 1e-3, y * 1e-3);
    }
    if (st.depths.empty()) throw FileError(file.string() + ": no data rows");
    return st;
}

ContourStack read_contours(const Record& rec)
{
    return read_contours_file(rec.file(rec.contours_file), rec.contour_theta_step_deg);
}

} // namespace drape::capture
