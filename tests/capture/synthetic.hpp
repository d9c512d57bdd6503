#pragma once
// Synthetic drape-lab records with known answers: a star-shaped hem
// r(theta) = R0 + A cos(n (theta - phase)) at the height an inextensible radial
// fibre of length R1 - R2 reaches, rasterised through the record's own camera
// model (4x supersampled, soft floor shadow, sensor noise, JPEG), plus the
// floor chessboards. Everything a test needs to know is computed here from the
// geometry, never copied from the code under test.
#include "engine/record/record.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

namespace synth {

constexpr double kPi = std::numbers::pi;

struct Spec {
    double R1 = 0.150, R2 = 0.075;     // [m]
    double R0 = 0.115, A = 0.015;      // hem radius mean / amplitude [m]
    int nodes = 7;
    double phase = 0.2;                // [rad]
    cv::Scalar fabric_bgr{62, 58, 150}; // burgundy
    bool fabric = true;                // false: empty stand
    bool boards = true;
    Eigen::Vector3d declared_t_offset = Eigen::Vector3d::Zero(); // error of the declared pose [m]
    unsigned seed = 7;
};

inline double hem_r(const Spec& s, double th) { return s.R0 + s.A * std::cos(s.nodes * (th - s.phase)); }
inline double hem_z(const Spec& s, double r)
{
    const double L = s.R1 - s.R2, d = r - s.R2;
    return -std::sqrt(std::max(L * L - d * d, 0.0));
}
/// Exact drape coefficient of the star: area = pi R0^2 + pi A^2 / 2.
inline double true_dc(const Spec& s)
{
    const double area = kPi * s.R0 * s.R0 + kPi * s.A * s.A / 2;
    return (area - kPi * s.R2 * s.R2) / (kPi * (s.R1 * s.R1 - s.R2 * s.R2)) * 100.0;
}

inline nlohmann::json camera_json(const Eigen::Vector3d& t_mm)
{
    return {{"image", "top.jpg"}, {"width", 1152}, {"height", 872}, {"fx", 1280.0}, {"fy", 1280.0},
            {"cx", 575.5}, {"cy", 435.5}, {"dist_coeffs", {0, 0, 0, 0, 0}},
            {"R_world_to_cam", {{1, 0, 0}, {0, -1, 0}, {0, 0, -1}}},
            {"t_world_to_cam_mm", {t_mm.x(), t_mm.y(), t_mm.z()}}};
}

inline nlohmann::json meta_json(const Spec& s)
{
    const Eigen::Vector3d t_mm = Eigen::Vector3d(0, 0, 880) + s.declared_t_offset * 1e3;
    nlohmann::json boards = nlohmann::json::array();
    if (s.boards) {
        boards.push_back({{"name", "E"}, {"x0_mm", 230}, {"y0_mm", -150}, {"nx", 7}, {"ny", 12}, {"square_mm", 25}, {"z_mm", -120}});
        boards.push_back({{"name", "W"}, {"x0_mm", -405}, {"y0_mm", -150}, {"nx", 7}, {"ny", 12}, {"square_mm", 25}, {"z_mm", -120}});
        boards.push_back({{"name", "N"}, {"x0_mm", -150}, {"y0_mm", 230}, {"nx", 12}, {"ny", 4}, {"square_mm", 25}, {"z_mm", -120}});
        boards.push_back({{"name", "S"}, {"x0_mm", -150}, {"y0_mm", -330}, {"nx", 12}, {"ny", 4}, {"square_mm", 25}, {"z_mm", -120}});
    }
    return {{"specimen_id", "SYN"},
            {"configuration", {{"specimen_diameter_D1_mm", s.R1 * 2e3}, {"support_disc_diameter_D2_mm", s.R2 * 2e3},
                               {"pedestal_height_mm", 120.0}, {"specimen_centred", true}}},
            {"fabric", {{"areal_density_g_m2", 200.0}, {"thickness_mm", 0.5}, {"colour", "synthetic"}}},
            {"units", {{"length", "mm"}, {"angles", "deg"}}},
            {"cameras", {{"top", camera_json(t_mm)}}},
            {"calibration_boards", boards}};
}

/// The lab's image size and intrinsics (1152 x 872 px, f 1280 px), no pose.
inline drape::record::Camera lab_intrinsics()
{
    drape::record::Camera c;
    c.width = 1152;
    c.height = 872;
    c.fx = c.fy = 1280;
    c.cx = 575.5;
    c.cy = 435.5;
    return c;
}

/// The true top camera (declared pose without the offset).
inline drape::record::Camera true_camera()
{
    drape::record::Camera c = lab_intrinsics();
    c.R << 1, 0, 0, 0, -1, 0, 0, 0, -1;
    c.t = Eigen::Vector3d(0, 0, 0.88);
    return c;
}

inline cv::Mat render_top(const Spec& s)
{
    constexpr int ss = 4; // supersampling
    const auto cam = true_camera();
    cv::Mat big(cam.height * ss, cam.width * ss, CV_8UC3, cv::Scalar(222, 224, 224));
    auto P = [&](const Eigen::Vector3d& X) {
        const Eigen::Vector2d u = cam.project(X);
        // pixel centres at integers: supersampled centre of pixel i is at ss*i + (ss-1)/2
        return cv::Point(static_cast<int>(std::lround((u.x() * ss + (ss - 1) / 2.0) * 16)),
                         static_cast<int>(std::lround((u.y() * ss + (ss - 1) / 2.0) * 16)));
    };
    if (s.boards) {
        struct B { double x0, y0; int nx, ny; };
        for (const B b : {B{0.230, -0.150, 7, 12}, B{-0.405, -0.150, 7, 12}, B{-0.150, 0.230, 12, 4}, B{-0.150, -0.330, 12, 4}})
            for (int i = 0; i < b.nx; ++i)
                for (int j = 0; j < b.ny; ++j) {
                    if ((i + j) % 2) continue;
                    const double x = b.x0 + 0.025 * i, y = b.y0 + 0.025 * j;
                    std::vector<cv::Point> q{P({x, y, -0.12}), P({x + 0.025, y, -0.12}), P({x + 0.025, y + 0.025, -0.12}),
                                             P({x, y + 0.025, -0.12})};
                    cv::fillConvexPoly(big, q, cv::Scalar(30, 30, 30), cv::LINE_8, 4);
                }
    }
    // Pedestal top, grey: seen when there is no fabric.
    std::vector<cv::Point> disc;
    for (int k = 0; k < 720; ++k) {
        const double th = 2 * kPi * k / 720;
        disc.push_back(P({s.R2 * std::cos(th), s.R2 * std::sin(th), 0.0}));
    }
    cv::fillPoly(big, std::vector<std::vector<cv::Point>>{disc}, cv::Scalar(150, 150, 150), cv::LINE_8, 4);
    cv::Mat img;
    cv::resize(big, img, cv::Size(cam.width, cam.height), 0, 0, cv::INTER_AREA);
    if (s.fabric) {
        // Fabric coverage at 4x (anti-aliased edge), a soft grey floor shadow
        // at 1x, composed in float: shadow under the fabric, fabric on top.
        std::vector<cv::Point> hem, shadow;
        for (int k = 0; k < 2880; ++k) {
            const double th = 2 * kPi * k / 2880, r = hem_r(s, th);
            hem.push_back(P({r * std::cos(th), r * std::sin(th), hem_z(s, r)}));
            const Eigen::Vector2d u = cam.project({(r + 0.004) * std::cos(th), (r + 0.004) * std::sin(th), -0.12});
            shadow.emplace_back(static_cast<int>(std::lround(u.x() * 16)), static_cast<int>(std::lround(u.y() * 16)));
        }
        cv::Mat cover_big = cv::Mat::zeros(big.size(), CV_8U);
        cv::fillPoly(cover_big, std::vector<std::vector<cv::Point>>{hem}, cv::Scalar(255), cv::LINE_8, 4);
        cv::Mat cover, sh = cv::Mat::zeros(img.size(), CV_32F);
        cv::resize(cover_big, cover, img.size(), 0, 0, cv::INTER_AREA);
        cover.convertTo(cover, CV_32F, 1.0 / 255);
        cv::fillPoly(sh, std::vector<std::vector<cv::Point>>{shadow}, cv::Scalar(1.0), cv::LINE_AA, 4);
        cv::GaussianBlur(sh, sh, cv::Size(0, 0), 6.0);
        cv::Mat f;
        img.convertTo(f, CV_32FC3);
        for (int y = 0; y < f.rows; ++y)
            for (int x = 0; x < f.cols; ++x) {
                const float a = cover.at<float>(y, x), d = 1.0f - 0.45f * sh.at<float>(y, x);
                cv::Vec3f& v = f.at<cv::Vec3f>(y, x);
                for (int c = 0; c < 3; ++c)
                    v[c] = a * static_cast<float>(s.fabric_bgr[c]) + (1 - a) * v[c] * d;
            }
        f.convertTo(img, CV_8UC3);
    }
    cv::Mat noise(img.size(), CV_16SC3);
    cv::RNG rng(s.seed);
    rng.fill(noise, cv::RNG::NORMAL, 0, 3);
    cv::Mat img16;
    img.convertTo(img16, CV_16SC3);
    img16 += noise;
    img16.convertTo(img, CV_8UC3);
    return img;
}

/// A side camera of its own (not the lab's): `dist` from the axis at azimuth
/// `az` (0: on -y looking along +y), `height` above the disc top, aimed at the
/// pedestal's middle; 1152 x 872 px, f 1280 px.
inline drape::record::Camera side_camera(double dist, double az, double height)
{
    drape::record::Camera c = lab_intrinsics();
    const Eigen::Vector3d C(dist * std::sin(az), -dist * std::cos(az), height), target(0, 0, -0.06);
    const Eigen::Vector3d zc = (target - C).normalized();
    const Eigen::Vector3d xc = zc.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d yc = zc.cross(xc);
    c.R.row(0) = xc.transpose();
    c.R.row(1) = yc.transpose();
    c.R.row(2) = zc.transpose();
    c.t = -c.R * C;
    return c;
}

inline nlohmann::json side_camera_json(const drape::record::Camera& c)
{
    nlohmann::json R = nlohmann::json::array();
    for (int i = 0; i < 3; ++i) R.push_back({c.R(i, 0), c.R(i, 1), c.R(i, 2)});
    return {{"image", "side.jpg"}, {"width", c.width}, {"height", c.height}, {"fx", c.fx}, {"fy", c.fy}, {"cx", c.cx}, {"cy", c.cy},
            {"dist_coeffs", {0, 0, 0, 0, 0}}, {"R_world_to_cam", R}, {"t_world_to_cam_mm", {c.t.x() * 1e3, c.t.y() * 1e3, c.t.z() * 1e3}}};
}

/// The side photo by ray casting (3 x 3 samples a pixel): a lit grey pedestal of
/// radius `pedestal_r` from the disc top down to the floor (z = -0.12 m), a white
/// floor, a dark backdrop, and a burgundy sleeve of cloth `cloth_drop` deep,
/// 12 mm outside the pedestal, hanging over its upper part.
inline cv::Mat render_side(const drape::record::Camera& cam, double pedestal_r, double cloth_drop, unsigned seed)
{
    const double h = 0.12, rc = pedestal_r + 0.012;
    const Eigen::Vector3d o = cam.centre(), light = Eigen::Vector3d(-0.5, -1.0, 0.6).normalized();
    auto hit_cylinder = [&](const Eigen::Vector3d& d, double r, double zlo, double zhi, double& s_hit) {
        const double a = d.x() * d.x() + d.y() * d.y(), b = 2 * (o.x() * d.x() + o.y() * d.y()), c = o.x() * o.x() + o.y() * o.y() - r * r;
        const double disc = b * b - 4 * a * c;
        if (disc < 0 || a <= 0) return false;
        const double s = (-b - std::sqrt(disc)) / (2 * a);
        const double z = o.z() + s * d.z();
        if (s <= 0 || z < zlo || z > zhi) return false;
        s_hit = s;
        return true;
    };
    cv::Mat img(cam.height, cam.width, CV_8UC3);
    for (int v = 0; v < cam.height; ++v)
        for (int u = 0; u < cam.width; ++u) {
            Eigen::Vector3d acc = Eigen::Vector3d::Zero(); // B, G, R
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) {
                    const Eigen::Vector3d d = cam.ray({u + (i - 1) / 3.0, v + (j - 1) / 3.0});
                    double s = 0;
                    if (cloth_drop > 0 && hit_cylinder(d, rc, -cloth_drop, 0.0, s)) {
                        acc += Eigen::Vector3d(62, 58, 150);
                    } else if (hit_cylinder(d, pedestal_r, -h, 0.0, s)) {
                        const Eigen::Vector3d X = o + s * d;
                        const Eigen::Vector3d n(X.x(), X.y(), 0);
                        const double g = 90 + 70 * std::max(0.0, n.normalized().dot(light));
                        acc += Eigen::Vector3d(g, g, g);
                    } else if (d.z() < 0) { // the floor, below the camera's horizon
                        acc += Eigen::Vector3d(238, 240, 240);
                    } else {
                        acc += Eigen::Vector3d(70, 70, 72);
                    }
                }
            acc /= 9;
            img.at<cv::Vec3b>(v, u) = cv::Vec3b(cv::saturate_cast<uchar>(acc[0]), cv::saturate_cast<uchar>(acc[1]), cv::saturate_cast<uchar>(acc[2]));
        }
    cv::Mat noise(img.size(), CV_16SC3), img16;
    cv::RNG rng(seed);
    rng.fill(noise, cv::RNG::NORMAL, 0, 3);
    img.convertTo(img16, CV_16SC3);
    img16 += noise;
    img16.convertTo(img, CV_8UC3);
    return img;
}

inline void write_record(const std::filesystem::path& dir, const Spec& s)
{
    std::filesystem::create_directories(dir);
    std::ofstream(dir / "meta.json") << meta_json(s).dump(1);
    cv::imwrite((dir / "top.jpg").string(), render_top(s), {cv::IMWRITE_JPEG_QUALITY, 92});
}

} // namespace synth
