#pragma once
// Synthetic single-camera drape photos with known answers: a phone-like camera
// (any height, off-axis, rolled about its optical axis, tilted) above a disc
// with a specimen (round or rectangular) draped on it. The hanging cloth is a
// straight inextensible fibre from the disc edge to the hem (the chord model),
// shaded by the light from above, so the disc rim shows as a shading step.
// Background, rig shadow, prints, a reverse side, sequins, printed ArUco
// markers or a chessboard at a declared height; 4x supersampled, noise, JPEG.
// Everything a test needs to know is computed here from the geometry.
#include "engine/record/record.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

namespace synth_photo {

constexpr double kPi = std::numbers::pi;

struct Scene {
    // Geometry [m].
    double R2 = 0.090;                  // disc radius (180 mm disc)
    bool rectangle = false;
    double R1 = 0.150;                  // round specimen radius
    double width = 0.30, length = 0.40, angle = 0.0; // rectangle [m, rad]
    double k0 = 0.55, k1 = 0.25;        // hem at R2 + L(theta) (k0 + k1 cos(n (theta - phase)))
    int nodes = 6;
    double phase = 0.3;
    // Camera.
    int width_px = 1280, height_px = 960;
    double f = 1100;                    // [px]
    double H = 0.70;                    // optical centre above the disc top [m]
    Eigen::Vector2d offset = Eigen::Vector2d::Zero(); // camera position off the axis [m]
    double roll_deg = 0, tilt_deg = 0;  // about the optical axis; about the image x axis
    // Looks.
    cv::Scalar cloth_bgr{60, 50, 170};   // front
    cv::Scalar reverse_bgr{-1, -1, -1};  // shown on the outer part of two sectors when >= 0
    cv::Scalar background_bgr{205, 208, 210};
    cv::Scalar clamp_bgr{-1, -1, -1};    // an upper disc on the cloth when >= 0
    double ambient = 0.45;               // shading: ambient + (1 - ambient) * cos(slope)
    bool print = false;                  // coloured blobs on the cloth (orange, yellow, green)
    bool print_white = false;            // ... and near-white ones (like the background)
    bool sequins = false;                // sparkles and dark specks on the cloth
    bool background_texture = false;     // a grainy table top
    bool rig_shadow = false;             // a dark soft band across the photo
    double shadow_depth = 0.45;
    // A scale reference.
    bool markers = false;                // ArUco DICT_4X4_50 at z = markers_z
    double marker_size = 0.05, markers_z = 0.0;
    bool chessboard = false;             // 7 x 5 squares of 25 mm at z = markers_z
    unsigned seed = 3;
};

inline double reach(const Scene& s, double th)
{
    if (!s.rectangle) return s.R1;
    const double t = th - s.angle, c = std::abs(std::cos(t)), sn = std::abs(std::sin(t));
    const double rx = c > 1e-12 ? 0.5 * s.width / c : 1e9, ry = sn > 1e-12 ? 0.5 * s.length / sn : 1e9;
    return std::min(rx, ry);
}
inline double hem_r(const Scene& s, double th)
{
    const double L = reach(s, th) - s.R2;
    return s.R2 + L * (s.k0 + s.k1 * std::cos(s.nodes * (th - s.phase)));
}
inline double hem_z(const Scene& s, double th)
{
    const double L = reach(s, th) - s.R2, d = hem_r(s, th) - s.R2;
    return -std::sqrt(std::max(L * L - d * d, 0.0));
}
inline double specimen_area(const Scene& s) { return s.rectangle ? s.width * s.length : kPi * s.R1 * s.R1; }

/// The true camera.
inline drape::record::Camera camera(const Scene& s)
{
    drape::record::Camera c;
    c.width = s.width_px;
    c.height = s.height_px;
    c.fx = c.fy = s.f;
    c.cx = (s.width_px - 1) / 2.0;
    c.cy = (s.height_px - 1) / 2.0;
    Eigen::Matrix3d base;
    base << 1, 0, 0, 0, -1, 0, 0, 0, -1; // looking down, image up = +y
    const Eigen::Matrix3d roll = Eigen::AngleAxisd(s.roll_deg * kPi / 180, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Matrix3d tilt = Eigen::AngleAxisd(s.tilt_deg * kPi / 180, Eigen::Vector3d::UnitX()).toRotationMatrix();
    c.R = tilt * roll * base;
    const Eigen::Vector3d C(s.offset.x(), s.offset.y(), s.H);
    c.t = -c.R * C;
    return c;
}

/// Area of the vertical projection of the drape [m^2] and the true D [%].
inline double true_area(const Scene& s)
{
    constexpr int n = 100000;
    double a = 0;
    for (int k = 0; k < n; ++k) {
        const double r = hem_r(s, 2 * kPi * k / n);
        a += 0.5 * r * r * 2 * kPi / n;
    }
    return a;
}
inline double true_dc(const Scene& s)
{
    return (true_area(s) - kPi * s.R2 * s.R2) / (specimen_area(s) - kPi * s.R2 * s.R2) * 100.0;
}
/// Area of the hem's image back-projected onto the plane z [m^2] (the
/// "uncorrected" outline in that plane), and the D it gives.
inline double plane_area(const Scene& s, double z)
{
    const auto cam = camera(s);
    double a = 0;
    constexpr int n = 20000;
    Eigen::Vector2d prev;
    for (int k = 0; k <= n; ++k) {
        const double th = 2 * kPi * k / n, r = hem_r(s, th);
        const auto u = cam.project({r * std::cos(th), r * std::sin(th), hem_z(s, th)});
        const Eigen::Vector2d p = cam.backproject_to_plane(u, z)->head<2>();
        if (k > 0) a += prev.x() * p.y() - p.x() * prev.y();
        prev = p;
    }
    return std::abs(a) / 2;
}
inline double plane_dc(const Scene& s, double z)
{
    return (plane_area(s, z) - kPi * s.R2 * s.R2) / (specimen_area(s) - kPi * s.R2 * s.R2) * 100.0;
}

namespace detail {
inline cv::Point2f P(const drape::record::Camera& cam, const Eigen::Vector3d& X, int ss)
{
    const Eigen::Vector2d u = cam.project(X);
    return {static_cast<float>(u.x() * ss + (ss - 1) / 2.0), static_cast<float>(u.y() * ss + (ss - 1) / 2.0)};
}
inline cv::Point Pi(const cv::Point2f& p) { return {static_cast<int>(std::lround(p.x * 16)), static_cast<int>(std::lround(p.y * 16))}; }
/// Draws a flat square image (marker, board) lying in the plane z at world
/// corners (x0, y0)..(x0 + side, y0 + side) into the supersampled image.
inline void paste_plane(cv::Mat& big, const cv::Mat& pattern, const drape::record::Camera& cam, double x0, double y0, double sx,
                        double sy, double z, int ss)
{
    std::vector<cv::Point2f> src{{0, 0}, {static_cast<float>(pattern.cols), 0},
                                 {static_cast<float>(pattern.cols), static_cast<float>(pattern.rows)},
                                 {0, static_cast<float>(pattern.rows)}};
    // Pattern top-left is world (x0, y0 + sy): image up = +y.
    std::vector<cv::Point2f> dst{P(cam, {x0, y0 + sy, z}, ss), P(cam, {x0 + sx, y0 + sy, z}, ss), P(cam, {x0 + sx, y0, z}, ss),
                                 P(cam, {x0, y0, z}, ss)};
    for (auto& p : dst) p += cv::Point2f(0.5f, 0.5f); // pixel-centre convention of warpPerspective
    for (auto& p : src) p -= cv::Point2f(0.5f, 0.5f);
    const cv::Mat Hm = cv::getPerspectiveTransform(src, dst);
    cv::Mat warped, mask;
    cv::warpPerspective(pattern, warped, Hm, big.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0, 0, 0));
    cv::Mat ones(pattern.size(), CV_8U, cv::Scalar(255));
    cv::warpPerspective(ones, mask, Hm, big.size(), cv::INTER_LINEAR, cv::BORDER_CONSTANT, cv::Scalar(0));
    warped.copyTo(big, mask > 127);
}
} // namespace detail

/// Marker centres on the sheet (world x, y at z = markers_z) by id.
inline std::vector<std::pair<int, Eigen::Vector2d>> marker_layout(const Scene& s)
{
    const double d = 1.3 * (s.rectangle ? 0.5 * std::hypot(s.width, s.length) : s.R1) + s.marker_size;
    return {{0, {-d, d}}, {1, {d, d}}, {2, {d, -d}}, {3, {-d, -d}}};
}

inline cv::Mat render(const Scene& s)
{
    using namespace detail;
    constexpr int ss = 4;
    const auto cam = camera(s);
    const cv::Size big_size(s.width_px * ss, s.height_px * ss);
    std::mt19937 rng(s.seed);
    // Background.
    cv::Mat big(big_size, CV_8UC3, s.background_bgr);
    if (s.background_texture) {
        cv::Mat grain(s.height_px / 4, s.width_px / 4, CV_32F);
        cv::randn(grain, 0, 1);
        cv::resize(grain, grain, big_size, 0, 0, cv::INTER_CUBIC);
        cv::GaussianBlur(grain, grain, {0, 0}, 6);
        for (int y = 0; y < big.rows; ++y)
            for (int x = 0; x < big.cols; ++x) {
                const float g = 14.0f * grain.at<float>(y, x) + 6.0f * std::sin(0.004f * static_cast<float>(y));
                cv::Vec3b& v = big.at<cv::Vec3b>(y, x);
                for (int c = 0; c < 3; ++c) v[c] = cv::saturate_cast<uchar>(v[c] + g);
            }
    }
    // Scale references on the plane z = markers_z.
    if (s.markers) {
        const auto dict = cv::aruco::getPredefinedDictionary(cv::aruco::DICT_4X4_50);
        for (const auto& [id, c] : marker_layout(s)) {
            cv::Mat m, m3;
            cv::aruco::drawMarker(dict, id, 240, m, 1);
            cv::Mat framed(320, 320, CV_8U, cv::Scalar(255)); // white quiet zone of one cell
            m.copyTo(framed(cv::Rect(40, 40, 240, 240)));
            cv::cvtColor(framed, m3, cv::COLOR_GRAY2BGR);
            const double side = s.marker_size * 320.0 / 240.0;
            paste_plane(big, m3, cam, c.x() - side / 2, c.y() - side / 2, side, side, s.markers_z, ss);
        }
    }
    if (s.chessboard) {
        constexpr int nx = 7, ny = 5, px = 60;
        cv::Mat board((ny + 2) * px, (nx + 2) * px, CV_8UC3, cv::Scalar(255, 255, 255));
        for (int i = 0; i < nx; ++i)
            for (int j = 0; j < ny; ++j)
                if ((i + j) % 2 == 0) cv::rectangle(board, cv::Rect((i + 1) * px, (j + 1) * px, px, px), cv::Scalar(20, 20, 20), cv::FILLED);
        const double sq = 0.025, x0 = -0.5 * (nx + 2) * sq;
        const double y0 = -(s.rectangle ? 0.5 * std::hypot(s.width, s.length) : s.R1) * 1.25 - (ny + 2) * sq;
        paste_plane(big, board, cam, x0, y0, (nx + 2) * sq, (ny + 2) * sq, s.markers_z, ss);
    }
    // The cloth: shade per sector, colour per pixel (print, reverse side).
    constexpr int sectors = 2880;
    cv::Mat shade(big_size, CV_32F, cv::Scalar(-1.0f)); // < 0: no cloth
    cv::Mat face(big_size, CV_8U, cv::Scalar(0));       // 1 = reverse side
    for (int k = 0; k < sectors; ++k) {
        const double a = 2 * kPi * k / sectors, b = 2 * kPi * (k + 1) / sectors, m = 0.5 * (a + b);
        const double L = reach(s, m) - s.R2, d = hem_r(s, m) - s.R2;
        const float sh = static_cast<float>(s.ambient + (1 - s.ambient) * d / L);
        auto pt = [&](double th, double frac) {
            const double r = s.R2 + frac * (hem_r(s, th) - s.R2), z = frac * hem_z(s, th);
            return Pi(P(cam, {r * std::cos(th), r * std::sin(th), z}, ss));
        };
        const bool reverse = s.reverse_bgr[0] >= 0 && (std::abs(std::remainder(m - 1.0, 2 * kPi)) < 0.3 ||
                                                      std::abs(std::remainder(m - 3.6, 2 * kPi)) < 0.25);
        std::vector<cv::Point> q{pt(a, 0), pt(b, 0), pt(b, 1), pt(a, 1)};
        cv::fillConvexPoly(shade, q, cv::Scalar(sh), cv::LINE_8, 4);
        if (reverse) {
            std::vector<cv::Point> r{pt(a, 0.55), pt(b, 0.55), pt(b, 1), pt(a, 1)};
            cv::fillConvexPoly(face, r, cv::Scalar(1), cv::LINE_8, 4);
        }
    }
    std::vector<cv::Point> top;
    for (int k = 0; k < 720; ++k) {
        const double th = 2 * kPi * k / 720;
        top.push_back(Pi(P(cam, {s.R2 * std::cos(th), s.R2 * std::sin(th), 0.0}, ss)));
    }
    cv::fillPoly(shade, std::vector<std::vector<cv::Point>>{top}, cv::Scalar(1.0f), cv::LINE_8, 4);
    cv::Mat print_map;
    if (s.print) {
        // Blobs of three colours over the cloth, in image space.
        print_map = cv::Mat(big_size, CV_8U, cv::Scalar(0));
        std::uniform_real_distribution<double> ux(0, big_size.width), uy(0, big_size.height), ur(30, 90);
        std::uniform_int_distribution<int> uc(1, 3);
        for (int i = 0; i < 900; ++i)
            cv::circle(print_map, {static_cast<int>(ux(rng)), static_cast<int>(uy(rng))}, static_cast<int>(ur(rng)),
                       cv::Scalar(uc(rng)), cv::FILLED);
    }
    const cv::Vec3f print_colours[4] = {{0, 0, 0}, {40, 160, 230}, s.print_white ? cv::Vec3f(230, 220, 215) : cv::Vec3f(40, 210, 230),
                                        {30, 120, 40}}; // -, orange, near-white or yellow, green
    std::uniform_real_distribution<double> u01(0, 1);
    for (int y = 0; y < big.rows; ++y)
        for (int x = 0; x < big.cols; ++x) {
            const float sh = shade.at<float>(y, x);
            if (sh < 0) continue;
            cv::Vec3f c(static_cast<float>(s.cloth_bgr[0]), static_cast<float>(s.cloth_bgr[1]), static_cast<float>(s.cloth_bgr[2]));
            if (face.at<uchar>(y, x))
                c = cv::Vec3f(static_cast<float>(s.reverse_bgr[0]), static_cast<float>(s.reverse_bgr[1]), static_cast<float>(s.reverse_bgr[2]));
            else if (!print_map.empty() && print_map.at<uchar>(y, x))
                c = print_colours[print_map.at<uchar>(y, x)];
            c *= sh;
            if (s.sequins && (x / 6 + y / 6 * 7) % 5 == 0) {
                const double r = u01(rng);
                if (r < 0.25) c = cv::Vec3f(250, 250, 250);
                else if (r < 0.5) c *= 0.3f;
            }
            big.at<cv::Vec3b>(y, x) = cv::Vec3b(cv::saturate_cast<uchar>(c[0]), cv::saturate_cast<uchar>(c[1]), cv::saturate_cast<uchar>(c[2]));
        }
    if (s.clamp_bgr[0] >= 0) {
        std::vector<cv::Point> clamp;
        for (int k = 0; k < 720; ++k) {
            const double th = 2 * kPi * k / 720;
            clamp.push_back(Pi(P(cam, {s.R2 * std::cos(th), s.R2 * std::sin(th), 0.0}, ss)));
        }
        cv::fillPoly(big, std::vector<std::vector<cv::Point>>{clamp}, s.clamp_bgr, cv::LINE_8, 4);
    }
    cv::Mat img;
    cv::resize(big, img, cv::Size(s.width_px, s.height_px), 0, 0, cv::INTER_AREA);
    // Lens blur of about a pixel.
    cv::GaussianBlur(img, img, {0, 0}, 0.7);
    // Shadows: the cloth's own soft contact shadow on the floor, and the rig's.
    cv::Mat sh = cv::Mat::zeros(img.size(), CV_32F);
    if (s.rig_shadow) {
        std::vector<cv::Point> band{{static_cast<int>(0.55 * s.width_px), 0}, {s.width_px, 0}, {s.width_px, s.height_px},
                                    {static_cast<int>(0.62 * s.width_px), s.height_px}};
        cv::fillConvexPoly(sh, band, cv::Scalar(1.0));
        cv::GaussianBlur(sh, sh, {0, 0}, 10);
    }
    cv::Mat f;
    img.convertTo(f, CV_32FC3);
    for (int y = 0; y < f.rows; ++y)
        for (int x = 0; x < f.cols; ++x) f.at<cv::Vec3f>(y, x) *= 1.0f - static_cast<float>(s.shadow_depth) * sh.at<float>(y, x);
    cv::Mat noise(img.size(), CV_32FC3);
    cv::RNG cvrng(s.seed);
    cvrng.fill(noise, cv::RNG::NORMAL, 0, 2.5);
    f += noise;
    f.convertTo(img, CV_8UC3);
    return img;
}

/// Writes photo.jpg (quality 92) in `dir`, returns its path.
inline std::filesystem::path write_photo(const std::filesystem::path& dir, const Scene& s, const std::string& name = "photo.jpg")
{
    std::filesystem::create_directories(dir);
    const auto p = dir / name;
    cv::imwrite(p.string(), render(s), {cv::IMWRITE_JPEG_QUALITY, 92});
    return p;
}

/// The minimal single-camera meta.json for a scene.
inline nlohmann::json meta(const Scene& s, const std::string& scale = "disc", const std::string& image = "photo.jpg")
{
    nlohmann::json conf = {{"support_disc_diameter_D2_mm", 2e3 * s.R2}};
    if (s.rectangle)
        conf["specimen"] = {{"shape", "rectangle"}, {"width_mm", 1e3 * s.width}, {"length_mm", 1e3 * s.length}, {"angle_deg", s.angle * 180 / kPi}};
    else
        conf["specimen_diameter_D1_mm"] = 2e3 * s.R1;
    nlohmann::json sc = {{"source", scale}};
    if (scale == "markers") {
        sc["size_mm"] = 1e3 * s.marker_size;
        sc["height_mm"] = 1e3 * s.markers_z;
    }
    if (scale == "chessboard") {
        sc["inner_corners"] = {6, 4};
        sc["square_mm"] = 25;
        sc["height_mm"] = 1e3 * s.markers_z;
    }
    return {{"specimen_id", "PHOTO"}, {"configuration", conf}, {"top_photo", {{"image", image}, {"scale", sc}}}};
}

inline void write_record(const std::filesystem::path& dir, const Scene& s, const nlohmann::json& m)
{
    write_photo(dir, s, m["top_photo"]["image"].get<std::string>());
    std::ofstream(dir / "meta.json") << m.dump(1);
}

} // namespace synth_photo
