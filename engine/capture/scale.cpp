#include "engine/capture/scale.hpp"

#include "engine/capture/image.hpp"
#include "engine/capture/pixels.hpp"
#include "engine/core/error.hpp"

#include <opencv2/aruco.hpp>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <limits>
#include <cmath>
#include <map>
#include <numeric>
#include <random>

namespace drape::capture {

using namespace detail;

namespace {

/// A camera whose world frame has its origin where the ray through `u0` meets
/// the plane z = 0 (the disc top), +z = `up_cam` (camera coordinates, towards
/// the camera), +x = the image's right direction projected into the plane.
/// `H` is the camera's height above that plane [m].
record::Camera camera_from_plane(int width, int height, double f, double cx, double cy, const Eigen::Vector3d& up_cam,
                                 double H, const Eigen::Vector2d& u0)
{
    record::Camera c;
    c.name = "top";
    c.width = width;
    c.height = height;
    c.fx = c.fy = f;
    c.cx = cx;
    c.cy = cy;
    const Eigen::Vector3d ez = up_cam.normalized();
    const Eigen::Vector3d r((u0.x() - cx) / f, (u0.y() - cy) / f, 1.0);
    const double den = ez.dot(r);
    const double lambda = den < -1e-9 ? -H / den : H;
    const Eigen::Vector3d O = lambda * r;
    Eigen::Vector3d ex = Eigen::Vector3d::UnitX() - ez.x() * ez;
    if (ex.norm() < 1e-6) ex = Eigen::Vector3d::UnitY() - ez.y() * ez;
    ex.normalize();
    const Eigen::Vector3d ey = ez.cross(ex);
    c.R.col(0) = ex;
    c.R.col(1) = ey;
    c.R.col(2) = ez;
    c.t = O;
    return c;
}

double diag_px(int w, int h) { return std::hypot(static_cast<double>(w), static_cast<double>(h)); }

/// A phone's main camera: about 26 mm focal length, 35 mm equivalent, i.e.
/// 26 / 43.3 of the image diagonal. The assumption when nothing else tells.
double prior_focal(int w, int h) { return 0.60 * diag_px(w, h); }

struct Circle {
    Eigen::Vector2d c;
    double r = 0;
};

std::optional<Circle> circle_through(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c)
{
    const double d = 2 * (a.x() * (b.y() - c.y()) + b.x() * (c.y() - a.y()) + c.x() * (a.y() - b.y()));
    if (std::abs(d) < 1e-9) return std::nullopt;
    const double a2 = a.squaredNorm(), b2 = b.squaredNorm(), c2 = c.squaredNorm();
    Circle k;
    k.c = {(a2 * (b.y() - c.y()) + b2 * (c.y() - a.y()) + c2 * (a.y() - b.y())) / d,
           (a2 * (c.x() - b.x()) + b2 * (a.x() - c.x()) + c2 * (b.x() - a.x())) / d};
    k.r = (a - k.c).norm();
    return k;
}

/// Least-squares circle (algebraic fit, then Gauss-Newton on the distances).
Circle fit_circle(const std::vector<Eigen::Vector2d>& p, Circle k)
{
    for (int it = 0; it < 10; ++it) {
        Eigen::Matrix3d JtJ = Eigen::Matrix3d::Zero();
        Eigen::Vector3d Jtr = Eigen::Vector3d::Zero();
        for (const auto& q : p) {
            const Eigen::Vector2d d = q - k.c;
            const double n = std::max(d.norm(), 1e-9);
            const Eigen::Vector3d J(-d.x() / n, -d.y() / n, -1.0);
            const double res = n - k.r;
            JtJ += J * J.transpose();
            Jtr += J * res;
        }
        const Eigen::Vector3d step = JtJ.ldlt().solve(-Jtr);
        k.c += step.head<2>();
        k.r += step.z();
        if (step.norm() < 1e-6) break;
    }
    return k;
}

struct EdgePoint {
    int ray;
    Eigen::Vector2d p;
};

} // namespace

std::optional<DiscRim> find_disc_rim(const cv::Mat& lab, const Eigen::Vector2d& centre_guess, double r_min, double r_max)
{
    constexpr int kRays = 360;
    constexpr double step = 0.5;
    r_min = std::max(r_min, 3.0);
    if (!(r_max > r_min + 4)) return std::nullopt;
    const int n = static_cast<int>((r_max - r_min) / step) + 1;
    std::vector<cv::Mat> ch;
    cv::split(lab, ch);
    static const char* names[3] = {"L*", "a*", "b*"};
    // Candidates per (channel, sign): the strongest radial step on each ray,
    // and the second strongest (prints and folds make other edges).
    std::vector<EdgePoint> cand[3][2];
    std::vector<double> prof(static_cast<std::size_t>(n)), d(static_cast<std::size_t>(n));
    for (int k = 0; k < kRays; ++k) {
        const double th = 2 * M_PI * k / kRays;
        const Eigen::Vector2d dir(std::cos(th), std::sin(th));
        for (int c = 0; c < 3; ++c) {
            for (int i = 0; i < n; ++i) {
                const Eigen::Vector2d q = centre_guess + (r_min + i * step) * dir;
                prof[static_cast<std::size_t>(i)] = bilinear(ch[static_cast<std::size_t>(c)], q.x(), q.y());
            }
            // Derivative over +-1 px (the image is already smoothed by 1 px).
            std::fill(d.begin(), d.end(), 0.0);
            for (int i = 2; i + 2 < n; ++i)
                d[static_cast<std::size_t>(i)] = (prof[static_cast<std::size_t>(i + 2)] - prof[static_cast<std::size_t>(i - 2)]) / (4 * step);
            std::vector<double> mag(d.size());
            for (std::size_t i = 0; i < d.size(); ++i) mag[i] = std::abs(d[i]);
            const double noise = median(mag);
            for (int sgn = 0; sgn < 2; ++sgn) {
                const double s = sgn == 0 ? 1.0 : -1.0;
                // Up to two local maxima of s*d.
                std::vector<std::pair<double, int>> peaks;
                for (int i = 3; i + 3 < n; ++i) {
                    const double v = s * d[static_cast<std::size_t>(i)];
                    if (v > s * d[static_cast<std::size_t>(i - 1)] && v >= s * d[static_cast<std::size_t>(i + 1)] &&
                        v > std::max(4 * noise, c == 0 ? 0.8 : 0.4))
                        peaks.emplace_back(v, i);
                }
                std::sort(peaks.rbegin(), peaks.rend());
                for (std::size_t j = 0; j < std::min<std::size_t>(2, peaks.size()); ++j) {
                    const int i = peaks[j].second;
                    const double ym = s * d[static_cast<std::size_t>(i - 1)], y0 = s * d[static_cast<std::size_t>(i)],
                                 yp = s * d[static_cast<std::size_t>(i + 1)];
                    const double den = ym - 2 * y0 + yp;
                    const double off = std::abs(den) > 1e-12 ? std::clamp(0.5 * (ym - yp) / den, -0.5, 0.5) : 0.0;
                    const double r = r_min + (i + off) * step;
                    cand[c][sgn].push_back({k, centre_guess + r * dir});
                }
            }
        }
    }
    std::optional<DiscRim> best;
    std::mt19937 rng(12345);
    for (int c = 0; c < 3; ++c)
        for (int sgn = 0; sgn < 2; ++sgn) {
            const auto& E = cand[c][sgn];
            if (E.size() < kRays / 4) continue;
            std::uniform_int_distribution<std::size_t> pick(0, E.size() - 1);
            auto support = [&](const Circle& k, std::vector<Eigen::Vector2d>* pts) {
                std::vector<double> bestd(kRays, 1e9);
                std::vector<Eigen::Vector2d> bestp(kRays);
                for (const auto& e : E) {
                    const double dd = std::abs((e.p - k.c).norm() - k.r);
                    if (dd < bestd[static_cast<std::size_t>(e.ray)]) {
                        bestd[static_cast<std::size_t>(e.ray)] = dd;
                        bestp[static_cast<std::size_t>(e.ray)] = e.p;
                    }
                }
                int count = 0;
                for (int k2 = 0; k2 < kRays; ++k2)
                    if (bestd[static_cast<std::size_t>(k2)] < 1.5) {
                        ++count;
                        if (pts) pts->push_back(bestp[static_cast<std::size_t>(k2)]);
                    }
                return count;
            };
            int best_count = 0;
            Circle best_k;
            for (int it = 0; it < 600; ++it) {
                const auto& a = E[pick(rng)];
                const auto& b = E[pick(rng)];
                const auto& e3 = E[pick(rng)];
                if (a.ray == b.ray || a.ray == e3.ray || b.ray == e3.ray) continue;
                const auto k = circle_through(a.p, b.p, e3.p);
                if (!k || k->r < r_min || k->r > r_max || (k->c - centre_guess).norm() > 0.3 * k->r) continue;
                const int cnt = support(*k, nullptr);
                if (cnt > best_count) {
                    best_count = cnt;
                    best_k = *k;
                }
            }
            if (best_count < kRays / 3) continue;
            std::vector<Eigen::Vector2d> pts;
            for (int rep = 0; rep < 3; ++rep) {
                pts.clear();
                support(best_k, &pts);
                best_k = fit_circle(pts, best_k);
            }
            pts.clear();
            const int cnt = support(best_k, &pts);
            double ss = 0;
            for (const auto& q : pts) ss += std::pow((q - best_k.c).norm() - best_k.r, 2);
            DiscRim rim;
            rim.centre_px = best_k.c;
            rim.radius_px = best_k.r;
            rim.ray_fraction = static_cast<double>(cnt) / kRays;
            rim.rms_px = std::sqrt(ss / std::max<std::size_t>(1, pts.size()));
            rim.edge = std::string(names[c]) + (sgn == 0 ? " rising outwards" : " falling outwards");
            rim.points_px = pts;
            if (pts.size() >= 6) {
                std::vector<cv::Point2f> cp;
                for (const auto& q : pts) cp.emplace_back(static_cast<float>(q.x()), static_cast<float>(q.y()));
                const cv::RotatedRect e = cv::fitEllipse(cp);
                const double a = std::max(e.size.width, e.size.height), b = std::min(e.size.width, e.size.height);
                rim.axis_ratio = a > 0 ? b / a : 1.0;
                rim.ellipse_angle_deg = e.size.width >= e.size.height ? e.angle : e.angle + 90.0;
                // Scale of the plane from the ellipse's area (first order in the tilt).
                rim.radius_px = 0.5 * std::sqrt(a * b); // a, b are full axes
                rim.centre_px = {e.center.x, e.center.y};
            }
            if (!best || rim.ray_fraction > best->ray_fraction + 0.05 ||
                (rim.ray_fraction > best->ray_fraction - 0.05 && rim.rms_px < best->rms_px))
                best = rim;
        }
    if (best && best->ray_fraction < 0.5) return std::nullopt;
    return best;
}

std::vector<MarkerSeen> find_markers(const cv::Mat& bgr, const std::string& dictionary)
{
    static const std::map<std::string, int> dicts = {
        {"DICT_4X4_50", cv::aruco::DICT_4X4_50},       {"DICT_4X4_100", cv::aruco::DICT_4X4_100},
        {"DICT_4X4_250", cv::aruco::DICT_4X4_250},     {"DICT_4X4_1000", cv::aruco::DICT_4X4_1000},
        {"DICT_5X5_50", cv::aruco::DICT_5X5_50},       {"DICT_5X5_100", cv::aruco::DICT_5X5_100},
        {"DICT_5X5_250", cv::aruco::DICT_5X5_250},     {"DICT_5X5_1000", cv::aruco::DICT_5X5_1000},
        {"DICT_6X6_50", cv::aruco::DICT_6X6_50},       {"DICT_6X6_100", cv::aruco::DICT_6X6_100},
        {"DICT_6X6_250", cv::aruco::DICT_6X6_250},     {"DICT_6X6_1000", cv::aruco::DICT_6X6_1000},
        {"DICT_7X7_50", cv::aruco::DICT_7X7_50},       {"DICT_7X7_100", cv::aruco::DICT_7X7_100},
        {"DICT_7X7_250", cv::aruco::DICT_7X7_250},     {"DICT_7X7_1000", cv::aruco::DICT_7X7_1000},
        {"DICT_ARUCO_ORIGINAL", cv::aruco::DICT_ARUCO_ORIGINAL},
        {"DICT_APRILTAG_16h5", cv::aruco::DICT_APRILTAG_16h5}, {"DICT_APRILTAG_25h9", cv::aruco::DICT_APRILTAG_25h9},
        {"DICT_APRILTAG_36h10", cv::aruco::DICT_APRILTAG_36h10}, {"DICT_APRILTAG_36h11", cv::aruco::DICT_APRILTAG_36h11},
    };
    const auto it = dicts.find(dictionary);
    if (it == dicts.end()) {
        std::string known;
        for (const auto& [k, v] : dicts) known += (known.empty() ? "" : ", ") + k;
        throw FileError("top_photo.scale.dictionary: unknown ArUco dictionary '" + dictionary + "' (known: " + known + ")");
    }
    const auto dict = cv::aruco::getPredefinedDictionary(it->second);
    auto params = cv::aruco::DetectorParameters::create();
    params->cornerRefinementMethod = cv::aruco::CORNER_REFINE_SUBPIX;
    std::vector<std::vector<cv::Point2f>> corners;
    std::vector<int> ids;
    cv::aruco::detectMarkers(bgr, dict, corners, ids, params);
    std::vector<MarkerSeen> out;
    for (std::size_t i = 0; i < ids.size(); ++i) {
        MarkerSeen m;
        m.id = ids[i];
        for (const auto& p : corners[i]) m.corners_px.emplace_back(p.x, p.y);
        out.push_back(m);
    }
    std::sort(out.begin(), out.end(), [](const MarkerSeen& a, const MarkerSeen& b) { return a.id < b.id; });
    return out;
}

namespace {

/// How far each pixel's colour is from the floor's: the floor's L*a*b* as a
/// quadratic surface in the pixel position (light falls off across a floor),
/// fitted to the photo's border band with the outliers (markers, boards, cloth
/// that reaches the border) dropped, twice. Distance with L* weighted 0.3, as the
/// segmentation weighs it (a shadow changes L* and hardly a*, b*). Also returns the
/// border's own spread (the robust sd of its distances).
cv::Mat floor_deviation(const cv::Mat& small_bgr, double& border_sd)
{
    const cv::Mat lab = to_lab(small_bgr);
    const int W = lab.cols, H = lab.rows;
    const int bx = std::max(2, W / 25), by = std::max(2, H / 25);
    auto basis = [&](int x, int y) {
        const double u = 2.0 * x / W - 1, v = 2.0 * y / H - 1;
        Eigen::Matrix<double, 6, 1> b;
        b << 1, u, v, u * u, u * v, v * v;
        return b;
    };
    std::vector<cv::Point> band;
    for (int y = 0; y < H; y += 2)
        for (int x = 0; x < W; x += 2)
            if (x < bx || y < by || x >= W - bx || y >= H - by) band.emplace_back(x, y);
    constexpr double wL = 0.3;
    auto distance = [&](const cv::Vec3f& c, const Eigen::Matrix<double, 6, 3>& C, const Eigen::Matrix<double, 6, 1>& b) {
        const Eigen::Vector3d f = C.transpose() * b;
        return std::sqrt(wL * wL * (c[0] - f[0]) * (c[0] - f[0]) + (c[1] - f[1]) * (c[1] - f[1]) + (c[2] - f[2]) * (c[2] - f[2]));
    };
    std::vector<char> keep(band.size(), 1);
    Eigen::Matrix<double, 6, 3> C = Eigen::Matrix<double, 6, 3>::Zero();
    border_sd = 0;
    for (int pass = 0; pass < 3; ++pass) {
        Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
        Eigen::Matrix<double, 6, 3> rhs = Eigen::Matrix<double, 6, 3>::Zero();
        for (std::size_t i = 0; i < band.size(); ++i) {
            if (!keep[i]) continue;
            const auto b = basis(band[i].x, band[i].y);
            const cv::Vec3f c = lab.at<cv::Vec3f>(band[i]);
            A += b * b.transpose();
            rhs += b * Eigen::RowVector3d(c[0], c[1], c[2]);
        }
        C = A.ldlt().solve(rhs);
        std::vector<double> d(band.size());
        for (std::size_t i = 0; i < band.size(); ++i) d[i] = distance(lab.at<cv::Vec3f>(band[i]), C, basis(band[i].x, band[i].y));
        border_sd = 1.4826 * median(d);
        const double cut = std::max(3 * border_sd, 1.0);
        for (std::size_t i = 0; i < band.size(); ++i) keep[i] = d[i] <= cut;
    }
    cv::Mat dev(lab.size(), CV_32F);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) dev.at<float>(y, x) = static_cast<float>(distance(lab.at<cv::Vec3f>(y, x), C, basis(x, y)));
    return dev;
}

/// The component of `fg` that is large and central (area x (1 - distance from the
/// centre / half the diagonal)); empty when there is none.
cv::Mat large_central_component(const cv::Mat& fg)
{
    cv::Mat labels, stats, centroids;
    const int n = cv::connectedComponentsWithStats(fg, labels, stats, centroids, 8, CV_32S);
    int best = 0;
    double best_score = 0;
    const cv::Point2d mid(fg.cols / 2.0, fg.rows / 2.0);
    for (int i = 1; i < n; ++i) {
        const double area = stats.at<int>(i, cv::CC_STAT_AREA);
        const cv::Point2d c(centroids.at<double>(i, 0), centroids.at<double>(i, 1));
        const double dist = cv::norm(c - mid) / std::hypot(mid.x, mid.y);
        const double score = area * (1.0 - dist);
        if (score > best_score) {
            best_score = score;
            best = i;
        }
    }
    cv::Mat out = cv::Mat::zeros(fg.size(), CV_8U);
    if (best > 0) out = labels == best;
    return out;
}

} // namespace

cv::Mat rough_cloth_mask(const cv::Mat& bgr)
{
    const double s = std::min(1.0, 480.0 / std::max(bgr.cols, bgr.rows));
    cv::Mat small;
    cv::resize(bgr, small, {}, s, s, cv::INTER_AREA);
    const int bx = std::max(3, small.cols / 25), by = std::max(3, small.rows / 25);
    cv::Mat mask(small.size(), CV_8U, cv::Scalar(cv::GC_BGD)), bgd, fgd;
    cv::Rect rect(bx, by, small.cols - 2 * bx, small.rows - 2 * by);
    // GrabCut's k-means draws from the thread's OpenCV RNG: started as a process
    // starts it, so a photo's rough mask (and the disc centre taken from it) is the
    // same alone or after other photos of a batch.
    cv::theRNG() = cv::RNG();
    cv::grabCut(detail::grabcut_input(small), mask, rect, bgd, fgd, 4, cv::GC_INIT_WITH_RECT);
    cv::Mat fg = (mask == cv::GC_FGD) | (mask == cv::GC_PR_FGD);
    const auto open = cv::getStructuringElement(cv::MORPH_ELLIPSE, {5, 5});
    cv::morphologyEx(fg, fg, cv::MORPH_OPEN, open);
    cv::Mat out = large_central_component(fg);
    // GrabCut's background model is learnt from the border alone: where light
    // falls off across the floor, the brighter floor near the middle can join the
    // cloth (a lab photo: the cloth's centroid 50 mm off the axis). Floor that is
    // the floor's colour where it lies leaves the cloth; when that would leave
    // little of it (cloth in the floor's colour), GrabCut's answer stands.
    double border_sd = 0;
    const cv::Mat dev = floor_deviation(small, border_sd);
    cv::Mat distinct = dev > std::max(6.0, 5 * border_sd);
    cv::morphologyEx(distinct, distinct, cv::MORPH_CLOSE, open);
    cv::Mat trimmed = out & distinct;
    cv::morphologyEx(trimmed, trimmed, cv::MORPH_OPEN, open);
    trimmed = large_central_component(trimmed);
    const int kept = cv::countNonZero(trimmed), had = cv::countNonZero(out);
    if (had > 0 && kept >= 0.25 * had) out = trimmed;
    cv::resize(out, out, bgr.size(), 0, 0, cv::INTER_NEAREST);
    return out;
}

namespace {

struct PlanePose {
    Eigen::Vector3d up_cam;   ///< plane normal towards the camera, camera coordinates
    double distance = 0;      ///< camera to the plane [m]
    double scale_px_per_m = 0;///< mean image scale of the reference in the plane
    double scale_sigma_rel = 0;
    std::string text;
    std::vector<std::string> warnings;
};

/// Plane pose of the scale reference for focal length f (markers or chessboard).
/// Throws RefusalError when it is not in the photo.
PlanePose reference_plane(const record::TopPhoto& tp, const ViewGeometry& g, double f, double cx, double cy)
{
    const cv::Matx33d K(f, 0, cx, 0, f, cy, 0, 0, 1);
    PlanePose pp;
    auto fix_sign = [](Eigen::Vector3d n, const Eigen::Vector3d& point_on_plane) {
        // Towards the camera (the camera is at the origin).
        if ((-point_on_plane).dot(n) < 0) n = -n;
        return n.normalized();
    };
    auto from_pnp = [&](const std::vector<cv::Point3d>& W, const std::vector<cv::Point2d>& I, int method) {
        cv::Mat rvec, tvec;
        cv::solvePnP(W, I, K, cv::Mat(), rvec, tvec, false, method);
        cv::Matx33d R;
        cv::Rodrigues(rvec, R);
        const Eigen::Vector3d n(R(0, 2), R(1, 2), R(2, 2));
        const Eigen::Vector3d t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
        const Eigen::Vector3d up = fix_sign(n, t);
        return std::pair{up, std::abs(up.dot(t))};
    };
    if (tp.scale == record::ScaleSource::Markers) {
        const double s = tp.marker_size;
        std::vector<double> scales;
        for (const auto& m : g.markers) {
            double side = 0;
            for (int i = 0; i < 4; ++i) side += (m.corners_px[static_cast<std::size_t>((i + 1) % 4)] - m.corners_px[static_cast<std::size_t>(i)]).norm();
            scales.push_back(side / 4 / s);
        }
        const double mean_scale = std::accumulate(scales.begin(), scales.end(), 0.0) / static_cast<double>(scales.size());
        double var = 0;
        for (double v : scales) var += (v - mean_scale) * (v - mean_scale);
        const double sd = scales.size() > 1 ? std::sqrt(var / static_cast<double>(scales.size() - 1)) : 0.0;
        pp.scale_px_per_m = mean_scale;
        // Corner placement ~0.2 px on each side, and the spread between markers.
        pp.scale_sigma_rel = std::hypot(0.2 / (mean_scale * s) / std::sqrt(4.0 * static_cast<double>(scales.size())),
                                        sd / mean_scale / std::sqrt(static_cast<double>(scales.size())));
        if (!tp.marker_layout.empty()) {
            std::vector<cv::Point3d> W;
            std::vector<cv::Point2d> I;
            int used = 0;
            for (const auto& m : g.markers) {
                const auto it = tp.marker_layout.find(m.id);
                if (it == tp.marker_layout.end()) continue;
                ++used;
                const double h = s / 2;
                const Eigen::Vector2d c = it->second;
                const double ox[4] = {-h, h, h, -h}, oy[4] = {h, h, -h, -h};
                for (int i = 0; i < 4; ++i) {
                    W.emplace_back(c.x() + ox[i], c.y() + oy[i], 0.0);
                    I.emplace_back(m.corners_px[static_cast<std::size_t>(i)].x(), m.corners_px[static_cast<std::size_t>(i)].y());
                }
            }
            if (used == 0)
                throw RefusalError({"markers-not-found", "none of the markers found (ids " + [&] {
                                        std::string ids;
                                        for (const auto& m : g.markers) ids += (ids.empty() ? "" : ", ") + std::to_string(m.id);
                                        return ids;
                                    }() + ") is in top_photo.scale.layout_mm",
                                    "check the dictionary and the layout's ids, or drop the layout to use the marker size alone"});
            const auto [up, dist] = from_pnp(W, I, used >= 2 ? cv::SOLVEPNP_ITERATIVE : cv::SOLVEPNP_IPPE);
            pp.up_cam = up;
            pp.distance = dist;
            pp.text = std::to_string(used) + " ArUco marker(s) of " + fmt("%.1f", 1e3 * s) + " mm on a sheet with a declared layout";
        } else {
            // Each marker alone (IPPE for a square), then the common plane.
            Eigen::Vector3d nsum = Eigen::Vector3d::Zero();
            std::vector<double> dists;
            for (const auto& m : g.markers) {
                const double h = s / 2;
                std::vector<cv::Point3d> W{{-h, h, 0}, {h, h, 0}, {h, -h, 0}, {-h, -h, 0}};
                std::vector<cv::Point2d> I;
                for (const auto& q : m.corners_px) I.emplace_back(q.x(), q.y());
                const auto [up, dist] = from_pnp(W, I, cv::SOLVEPNP_IPPE_SQUARE);
                nsum += up;
                dists.push_back(dist);
            }
            pp.up_cam = nsum.normalized();
            pp.distance = median(dists);
            if (dists.size() >= 2) {
                const auto [lo, hi] = std::minmax_element(dists.begin(), dists.end());
                if (*hi - *lo > 0.05 * pp.distance)
                    pp.warnings.push_back("the markers lie at different distances from the camera (" + fmt("%.0f", 1e3 * *lo) + " to " +
                                          fmt("%.0f", 1e3 * *hi) + " mm): are they all in one plane at the declared height?");
            }
            pp.text = std::to_string(g.markers.size()) + " ArUco marker(s) of " + fmt("%.1f", 1e3 * s) + " mm";
        }
        return pp;
    }
    // Chessboard.
    std::vector<cv::Point3d> W;
    std::vector<cv::Point2d> I;
    for (std::size_t i = 0; i < g.board_corners_px.size(); ++i) {
        const int c = static_cast<int>(i) % tp.board_cols, r = static_cast<int>(i) / tp.board_cols;
        W.emplace_back(c * tp.board_square, -r * tp.board_square, 0.0);
        I.emplace_back(g.board_corners_px[i].x(), g.board_corners_px[i].y());
    }
    const auto [up, dist] = from_pnp(W, I, cv::SOLVEPNP_ITERATIVE);
    pp.up_cam = up;
    pp.distance = dist;
    double side = 0;
    int ns = 0;
    for (std::size_t i = 0; i + 1 < g.board_corners_px.size(); ++i)
        if ((static_cast<int>(i) + 1) % tp.board_cols != 0) {
            side += (g.board_corners_px[i + 1] - g.board_corners_px[i]).norm();
            ++ns;
        }
    pp.scale_px_per_m = side / std::max(1, ns) / tp.board_square;
    pp.scale_sigma_rel = 0.1 / (pp.scale_px_per_m * tp.board_square) / std::sqrt(static_cast<double>(std::max(1, ns)));
    pp.text = "chessboard " + std::to_string(tp.board_cols) + " x " + std::to_string(tp.board_rows) + " inner corners, " +
              fmt("%.1f", 1e3 * tp.board_square) + " mm squares";
    return pp;
}

/// Radial extent of a rough mask around c: the given percentile of the
/// outermost mask pixel over 360 rays [px] (NaN when empty).
double mask_radius_percentile(const cv::Mat& mask, const Eigen::Vector2d& c, double q)
{
    if (mask.empty()) return kNaN;
    std::vector<double> r;
    const double rmax = std::hypot(mask.cols, mask.rows);
    for (int k = 0; k < 360; ++k) {
        const double th = 2 * M_PI * k / 360;
        double last = 0;
        for (double s = 0; s < rmax; s += 1.0) {
            const int x = static_cast<int>(std::lround(c.x() + s * std::cos(th))), y = static_cast<int>(std::lround(c.y() + s * std::sin(th)));
            if (x < 0 || y < 0 || x >= mask.cols || y >= mask.rows) break;
            if (mask.at<uchar>(y, x)) last = s;
        }
        r.push_back(last);
    }
    std::sort(r.begin(), r.end());
    return r[static_cast<std::size_t>(std::clamp(q, 0.0, 1.0) * (r.size() - 1))];
}

} // namespace

std::string bound_disc_centre(const record::Record& rec, const cv::Mat& region, ViewGeometry& g)
{
    if (g.disc || g.centre_source.rfind("centroid", 0) != 0) return "";
    const std::string what = "the disc centre is taken as the cloth's centroid (the rim was not found)";
    const std::string remedy = "; --disc-px X,Y,R gives it";
    const auto unbounded = [&] {
        return what + ": how far off it is cannot be bounded (the counted region does not hold the disc)" + remedy;
    };
    if (region.empty()) return unbounded();
    // The disc's smallest radius in the image (an ellipse under a tilted camera),
    // from the camera two of its height's uncertainties higher (a disc seen from
    // further away is smaller), less 2 px for the region's edge.
    const record::Camera cam = camera_with_height(g, g.camera_height + 2 * g.camera_height_sigma);
    const Eigen::Vector2d c0 = cam.project({0, 0, 0});
    double r_px = std::numeric_limits<double>::infinity();
    for (int k = 0; k < 16; ++k) {
        const double th = M_PI * k / 8;
        r_px = std::min(r_px, (cam.project({rec.R2 * std::cos(th), rec.R2 * std::sin(th), 0.0}) - c0).norm());
    }
    r_px -= 2;
    if (!(r_px > 2 && std::isfinite(r_px))) return unbounded();
    cv::Mat dist;
    cv::distanceTransform(fill_holes(region), dist, cv::DIST_L2, cv::DIST_MASK_PRECISE);
    double far = 0, ss = 0;
    int n = 0;
    for (int y = 0; y < dist.rows; ++y)
        for (int x = 0; x < dist.cols; ++x)
            if (dist.at<float>(y, x) >= r_px) {
                const double d = std::hypot(x - g.centre_px.x(), y - g.centre_px.y());
                far = std::max(far, d);
                ss += d * d;
                ++n;
            }
    if (n == 0) return unbounded();
    // In metres at the disc top under the camera as measured.
    const double px_per_m = (g.camera.project({rec.R2, 0, 0}) - g.camera.project({0, 0, 0})).norm() / rec.R2;
    g.centre_bound = far / px_per_m;
    g.centre_sigma = std::sqrt(ss / n) / px_per_m;
    return what + ": the disc, which the cloth covers, has its centre within " + fmt("%.0f", 1e3 * g.centre_bound) + " mm of it (" +
           fmt("%.0f", 1e3 * g.centre_sigma) + " mm RMS; D's term disc_centre)" + remedy;
}

record::Camera camera_with_height(const ViewGeometry& g, double H)
{
    if (!g.single_camera) return g.camera;
    const double h_ref = g.reference_distance;
    const double h_new = H - g.reference_height;
    const double f = g.focal_px * h_new / h_ref;
    return camera_from_plane(g.camera.width, g.camera.height, f, g.camera.cx, g.camera.cy, g.plane_normal_cam, H, g.centre_px);
}

namespace {

/// The photo's size and principal point (its centre).
struct Frame {
    int W = 0, H = 0;
    double cx = 0, cy = 0;
};

/// The disc rim (declared, or found around the cloth's rough centre) and the disc
/// centre: the rim's, the declared one, or the cloth's centroid.
void locate_disc(const record::Record& rec, const cv::Mat& lab, const cv::Mat& rough_cloth, const Frame& fr, ViewGeometry& g)
{
    const record::TopPhoto& tp = *rec.top_photo;
    // Where the cloth is, roughly, and how far it reaches from its centre.
    Eigen::Vector2d guess(fr.cx, fr.cy);
    if (!rough_cloth.empty() && cv::countNonZero(rough_cloth) > 0) {
        const cv::Moments mo = cv::moments(rough_cloth, true);
        guess = {mo.m10 / mo.m00, mo.m01 / mo.m00};
    }
    if (tp.disc_centre_px) guess = *tp.disc_centre_px;
    // The disc rim: declared, or found (needed for the disc scale; for the other
    // sources it places the disc centre and, at a second height, gives the camera
    // height).
    if (tp.disc_centre_px && tp.disc_radius_px) {
        DiscRim d;
        d.centre_px = *tp.disc_centre_px;
        d.radius_px = *tp.disc_radius_px;
        d.declared = true;
        d.ray_fraction = 1;
        d.edge = "declared in top_photo.disc_px";
        g.disc = d;
    } else {
        double r_lo = 0.02 * std::min(fr.W, fr.H), r_hi = 0.45 * std::min(fr.W, fr.H);
        const double p10 = mask_radius_percentile(rough_cloth, guess, 0.10);
        const double p50 = mask_radius_percentile(rough_cloth, guess, 0.50);
        if (std::isfinite(p10) && p10 > 10) {
            r_hi = 0.98 * p10;
            r_lo = 0.8 * p50 * rec.R2 / rec.specimen.max_reach();
        }
        g.disc = find_disc_rim(lab, guess, r_lo, r_hi);
        if (!g.disc && tp.scale == record::ScaleSource::Disc)
            throw RefusalError({"disc-not-found",
                                "the support disc's rim was not found in the photo (no circular edge between " + fmt("%.0f", r_lo) +
                                    " and " + fmt("%.0f", r_hi) + " px from the cloth's centre on at least half the rays)",
                                "give its position (--disc-px X,Y,R or top_photo.disc_px), or another scale: --scale markers, "
                                "--scale px-per-mm=N"});
    }
    if (g.disc) {
        g.centre_px = g.disc->centre_px;
        g.centre_source = g.disc->declared ? "declared (top_photo.disc_px)" : "disc rim found in the photo";
        if (!g.disc->declared && g.disc->axis_ratio < std::cos(8.0 * M_PI / 180))
            g.warnings.push_back("the disc rim is an ellipse (axis ratio " + fmt("%.3f", g.disc->axis_ratio) + ", ~" +
                                 fmt("%.0f", std::acos(g.disc->axis_ratio) * 180 / M_PI) +
                                 " deg of tilt): the scale is taken from its area; a tilted camera is better measured with markers");
    } else if (tp.disc_centre_px) {
        g.centre_px = *tp.disc_centre_px;
        g.centre_source = "declared (top_photo.disc_px)";
    } else {
        g.centre_px = guess;
        g.centre_source = "centroid of the cloth (disc rim not found)";
    }
}

/// The camera height the photo's record declares, with its sigma.
std::optional<std::pair<double, double>> declared_height(const record::TopPhoto& tp)
{
    if (!tp.camera_height) return std::nullopt;
    return std::pair{*tp.camera_height, tp.camera_height_sigma.value_or(std::max(0.01, 0.02 * *tp.camera_height))};
}

/// The scale from the disc rim or a declared px/mm: a camera looking straight
/// down (a tilt shows as an elliptical rim), its height declared, from the
/// declared focal length, or from a phone lens's prior.
void level_camera(const record::Record& rec, const Frame& fr, ViewGeometry& g)
{
    const record::TopPhoto& tp = *rec.top_photo;
    const Eigen::Vector3d up(0, 0, -1);
    double s_ref = 0;
    if (tp.scale == record::ScaleSource::Disc) {
        g.reference_height = tp.reference_height;
        g.reference_height_sigma = tp.reference_height_sigma.value_or(0.001);
        s_ref = g.disc->radius_px / rec.R2;
        const double fit = g.disc->rms_px / std::sqrt(std::max<std::size_t>(1, g.disc->points_px.size())) / g.disc->radius_px;
        g.scale_sigma_rel = std::hypot(fit, tp.disc_edge_sigma / rec.R2);
        g.source_text = "disc rim: " + fmt("%.1f", g.disc->radius_px) + " px radius = " + fmt("%.1f", 1e3 * rec.R2) + " mm" +
                        (g.disc->declared ? " (declared)" : " (found on " + fmt("%.0f", 100 * g.disc->ray_fraction) + " % of the rays, " +
                                                                g.disc->edge + ", RMS " + fmt("%.2f", g.disc->rms_px) + " px)");
    } else {
        g.reference_height = tp.reference_height;
        g.reference_height_sigma = tp.reference_height_sigma.value_or(0.002);
        s_ref = *tp.px_per_mm * 1e3;
        g.scale_sigma_rel = tp.px_per_mm_sigma_rel.value_or(0.005);
        g.source_text = fmt("%.4g", *tp.px_per_mm) + " px/mm at z = " + fmt("%.0f", 1e3 * g.reference_height) + " mm (declared)";
    }
    g.scale_px_per_m = s_ref;
    double f = 0, H = 0;
    if (auto dh = declared_height(tp)) {
        H = dh->first;
        g.camera_height_sigma = dh->second;
        f = s_ref * (H - g.reference_height);
        g.camera_height_source = "declared";
    } else if (tp.focal_px) {
        f = *tp.focal_px;
        H = f / s_ref + g.reference_height;
        g.camera_height_sigma = tp.focal_px_sigma_rel * H;
        g.camera_height_source = "from the " + tp.focal_px_source + " focal length (" + fmt("%.0f", f) + " px, +-" +
                                 fmt("%.0f", 100 * tp.focal_px_sigma_rel) + " %)";
    } else {
        f = prior_focal(fr.W, fr.H);
        H = f / s_ref + g.reference_height;
        g.camera_height_sigma = 0.3 * H;
        g.camera_height_known = false;
        g.camera_height_source = "assumed: a phone's 26 mm-equivalent lens (" + fmt("%.0f", f) +
                                 " px), +-30 %; declare top_photo.camera_height_mm or focal_px";
    }
    if (!(H - g.reference_height > 0.05))
        throw FileError("top_photo: the camera would be " + fmt("%.0f", 1e3 * (H - g.reference_height)) +
                        " mm above the scale reference; check camera_height_mm / focal_px");
    g.focal_px = f;
    g.plane_normal_cam = up;
    g.reference_distance = H - g.reference_height;
    g.camera_height = H;
    g.camera = camera_from_plane(fr.W, fr.H, f, fr.cx, fr.cy, up, H, g.centre_px);
}

/// The markers or the chessboard in the photo; refuses when they are not there.
void find_reference(const cv::Mat& bgr, const record::TopPhoto& tp, ViewGeometry& g)
{
    if (tp.scale == record::ScaleSource::Markers) {
        g.markers = find_markers(bgr, tp.marker_dictionary);
        if (g.markers.empty())
            throw RefusalError({"markers-not-found", "no " + tp.marker_dictionary + " marker found in the photo",
                                "check the dictionary (top_photo.scale.dictionary / --marker-dict) and that the markers are "
                                "sharp and whole, or use --scale disc / px-per-mm=N"});
        return;
    }
    cv::Mat grey;
    cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
    std::vector<cv::Point2f> corners;
    const bool found = cv::findChessboardCorners(grey, cv::Size(tp.board_cols, tp.board_rows), corners,
                                                 cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
    if (!found)
        throw RefusalError({"chessboard-not-found",
                            "no chessboard of " + std::to_string(tp.board_cols) + " x " + std::to_string(tp.board_rows) +
                                " inner corners found in the photo",
                            "check top_photo.scale.inner_corners (inner corners, not squares), or use another scale"});
    cv::cornerSubPix(grey, corners, cv::Size(5, 5), cv::Size(-1, -1), cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 40, 0.01));
    for (const auto& p : corners) g.board_corners_px.emplace_back(p.x, p.y);
}

/// The reference plane's pose for focal length f, and the camera it puts the disc under.
std::pair<PlanePose, record::Camera> camera_at_focal(const record::TopPhoto& tp, const ViewGeometry& g, const Frame& fr, double f)
{
    PlanePose pp = reference_plane(tp, g, f, fr.cx, fr.cy);
    const double H = pp.distance + g.reference_height;
    return std::pair{pp, camera_from_plane(fr.W, fr.H, f, fr.cx, fr.cy, pp.up_cam, H, g.centre_px)};
}

/// Two heights: the reference plane and the disc rim. The focal length whose camera
/// images the disc with the radius seen gives the camera height (a pinhole's scale
/// changes as 1 / (H - z)); its sigma from the rim's edge. Nothing when no focal
/// length fits (a warning says so).
std::optional<double> focal_from_two_heights(const record::Record& rec, const Frame& fr, ViewGeometry& g)
{
    const record::TopPhoto& tp = *rec.top_photo;
    const double f_prior = prior_focal(fr.W, fr.H);
    auto rim_radius = [&](double fv) {
        const record::Camera c = camera_at_focal(tp, g, fr, fv).second;
        const Eigen::Vector2d c0 = c.project({0, 0, 0});
        double s = 0;
        for (int k = 0; k < 36; ++k) {
            const double th = 2 * M_PI * k / 36;
            s += (c.project({rec.R2 * std::cos(th), rec.R2 * std::sin(th), 0.0}) - c0).norm();
        }
        return s / 36;
    };
    // The reference's distance grows in proportion to f: below f_min the camera
    // would sit below the disc top.
    const double per_f = camera_at_focal(tp, g, fr, f_prior).first.distance / f_prior;
    const double f_min = g.reference_height < 0 ? 1.02 * -g.reference_height / per_f : 0.05 * f_prior;
    auto solve = [&](double target) -> std::optional<double> {
        double lo = std::max(0.05 * f_prior, f_min), hi = 20 * f_prior;
        const double glo = rim_radius(lo) - target, ghi = rim_radius(hi) - target;
        if (!(glo * ghi < 0)) return std::nullopt;
        for (int it = 0; it < 60; ++it) {
            const double mid = std::sqrt(lo * hi);
            const double gm = rim_radius(mid) - target;
            ((gm < 0) == (glo < 0) ? lo : hi) = mid;
        }
        return std::sqrt(lo * hi);
    };
    const double r = g.disc->radius_px;
    const double dr = std::hypot(tp.disc_edge_sigma * r / rec.R2, 0.3);
    const auto f0 = solve(r), fa = solve(r + dr), fb = solve(r - dr);
    if (!f0) {
        g.warnings.push_back("the disc rim's size does not fit any camera height with the reference's: lens prior used");
        return std::nullopt;
    }
    const double H0 = camera_at_focal(tp, g, fr, *f0).first.distance + g.reference_height;
    double sig = 0.3 * H0;
    if (fa && fb) {
        const double Ha = camera_at_focal(tp, g, fr, *fa).first.distance + g.reference_height;
        const double Hb = camera_at_focal(tp, g, fr, *fb).first.distance + g.reference_height;
        sig = std::hypot(0.5 * std::abs(Ha - Hb), g.reference_height_sigma * H0 / std::abs(g.reference_height));
    }
    g.camera_height_sigma = sig;
    g.camera_height_source = "from two heights: the reference at z = " + fmt("%.0f", 1e3 * g.reference_height) + " mm and the disc rim at z = 0";
    return f0;
}

/// The focal length with markers or a chessboard: declared, the one that puts the
/// reference at the declared camera height, from two heights, or a phone lens's prior.
double reference_focal(const record::Record& rec, const Frame& fr, ViewGeometry& g)
{
    const record::TopPhoto& tp = *rec.top_photo;
    const double f_prior = prior_focal(fr.W, fr.H);
    double f = f_prior;
    if (tp.focal_px) {
        f = *tp.focal_px;
        g.camera_height_source = "from the reference's pose with the " + tp.focal_px_source + " focal length (" + fmt("%.0f", f) +
                                 " px, +-" + fmt("%.0f", 100 * tp.focal_px_sigma_rel) + " %)";
    } else if (auto dh = declared_height(tp)) {
        // Focal length such that the reference plane lies H - z_ref below the camera.
        double lo = 0.05 * f_prior, hi = 20 * f_prior;
        for (int it = 0; it < 60; ++it) {
            const double mid = std::sqrt(lo * hi);
            const double Hm = camera_at_focal(tp, g, fr, mid).first.distance + g.reference_height;
            (Hm < dh->first ? lo : hi) = mid;
        }
        f = std::sqrt(lo * hi);
        g.camera_height_source = "declared";
    } else if (g.disc && std::abs(g.reference_height) >= 0.015) {
        if (const auto f2 = focal_from_two_heights(rec, fr, g)) f = *f2;
    }
    if (g.camera_height_source.empty()) {
        g.camera_height_known = false;
        g.camera_height_source = "assumed: a phone's 26 mm-equivalent lens (" + fmt("%.0f", f) +
                                 " px), +-30 %; declare top_photo.camera_height_mm or focal_px, or put the markers at another "
                                 "height than the disc top";
    }
    return f;
}

} // namespace

namespace {

bool printed_reference(record::ScaleSource s) { return s == record::ScaleSource::Markers || s == record::ScaleSource::Chessboard; }

/// The record with the calibration photo's scale declaration in place of its own.
record::Record with_calibration_reference(const record::Record& rec, const ScaleCalibration& cal)
{
    record::Record r = rec;
    record::TopPhoto& tp = *r.top_photo;
    const record::TopPhoto& ref = cal.reference;
    tp.scale = ref.scale;
    tp.reference_height = ref.reference_height;
    tp.reference_height_sigma = ref.reference_height_sigma;
    tp.marker_dictionary = ref.marker_dictionary;
    tp.marker_size = ref.marker_size;
    tp.marker_layout = ref.marker_layout;
    tp.board_cols = ref.board_cols;
    tp.board_rows = ref.board_rows;
    tp.board_square = ref.board_square;
    return r;
}

} // namespace

void check_calibration_size(const ScaleCalibration& cal, const std::string& name, int width, int height)
{
    if (width == cal.width && height == cal.height) return;
    throw FileError(name + ": the photo is " + std::to_string(width) + " x " + std::to_string(height) + " px but the scale calibration photo " +
                    cal.photo + " is " + std::to_string(cal.width) + " x " + std::to_string(cal.height) +
                    " px: a scale read in one photo holds for another only from the same fixed camera at the same image size");
}

ScaleCalibration read_scale_calibration(const record::TopPhoto& reference, const std::filesystem::path& photo)
{
    if (!printed_reference(reference.scale))
        throw ParameterError(std::string("a scale calibration photo is read for markers or a chessboard, not for the scale source '") +
                             record::to_string(reference.scale) + "' (the disc rim is found in each photo; px/mm needs no photo)");
    ScaleCalibration cal;
    cal.photo = photo.string();
    cal.reference = reference;
    const cv::Mat bgr = load_photo_file(photo);
    cal.width = bgr.cols;
    cal.height = bgr.rows;
    ViewGeometry g;
    g.reference_height = reference.reference_height;
    const Frame fr{bgr.cols, bgr.rows, (bgr.cols - 1) / 2.0, (bgr.rows - 1) / 2.0};
    try {
        find_reference(bgr, reference, g);
        // The scale in the reference's plane does not depend on the focal length;
        // the plane's pose does, and is solved in each photo with that photo's lens.
        const PlanePose pp = reference_plane(reference, g, prior_focal(fr.W, fr.H), fr.cx, fr.cy);
        cal.scale_px_per_m = pp.scale_px_per_m;
        cal.scale_sigma_rel = pp.scale_sigma_rel;
        cal.description = pp.text + " at z = " + fmt("%.0f", 1e3 * reference.reference_height) + " mm: " +
                          fmt("%.5g", 1e-3 * pp.scale_px_per_m) + " px/mm (+-" + fmt("%.2f", 100 * pp.scale_sigma_rel) + " %)";
    } catch (const RefusalError& e) {
        throw FileError(cal.photo + ": scale calibration photo: " + e.refusal.message + " -- try: " + e.refusal.remedy);
    }
    cal.markers = std::move(g.markers);
    cal.board_corners_px = std::move(g.board_corners_px);
    return cal;
}

ViewGeometry solve_view(const record::Record& rec_in, const cv::Mat& bgr, const cv::Mat& lab, const cv::Mat& rough_cloth,
                        const ScaleCalibration* calibration)
{
    if (!rec_in.top_photo) throw ParameterError("solve_view: the record has no top_photo");
    std::optional<record::Record> calibrated;
    if (calibration) {
        if (!printed_reference(calibration->reference.scale))
            throw ParameterError("solve_view: a scale calibration holds markers or a chessboard");
        check_calibration_size(*calibration, rec_in.file(rec_in.top_image()).string(), bgr.cols, bgr.rows);
        calibrated = with_calibration_reference(rec_in, *calibration);
    }
    const record::Record& rec = calibrated ? *calibrated : rec_in;
    const record::TopPhoto& tp = *rec.top_photo;
    ViewGeometry g;
    g.single_camera = true;
    g.source = tp.scale;
    const Frame fr{bgr.cols, bgr.rows, (bgr.cols - 1) / 2.0, (bgr.rows - 1) / 2.0};
    locate_disc(rec, lab, rough_cloth, fr, g);
    if (tp.scale == record::ScaleSource::Disc || tp.scale == record::ScaleSource::PxPerMm) {
        level_camera(rec, fr, g);
        return g;
    }
    // Markers or a chessboard: a plane of known geometry at a declared height.
    g.reference_height = tp.reference_height;
    g.reference_height_sigma = tp.reference_height_sigma.value_or(0.001);
    if (calibration) {
        // Found once in the calibration photo: the same camera, so the same pixels.
        g.markers = calibration->markers;
        g.board_corners_px = calibration->board_corners_px;
        g.calibration_photo = calibration->photo;
    } else {
        find_reference(bgr, tp, g);
    }
    const double f = reference_focal(rec, fr, g);
    auto [pp, cam] = camera_at_focal(tp, g, fr, f);
    g.focal_px = f;
    g.plane_normal_cam = pp.up_cam;
    g.reference_distance = pp.distance;
    g.camera_height = pp.distance + g.reference_height;
    if (g.camera_height_sigma == 0)
        g.camera_height_sigma = (!g.camera_height_known ? 0.3 : tp.focal_px ? tp.focal_px_sigma_rel : 0.02) * g.camera_height;
    if (auto dh = declared_height(tp)) g.camera_height_sigma = dh->second;
    g.scale_px_per_m = pp.scale_px_per_m;
    g.scale_sigma_rel = pp.scale_sigma_rel;
    g.source_text = pp.text + (calibration ? " in " + calibration->photo : std::string()) + " at z = " + fmt("%.0f", 1e3 * g.reference_height) +
                    " mm";
    for (auto& w : pp.warnings) g.warnings.push_back(w);
    if (!(g.camera_height > 0.05)) throw FileError("top_photo: the camera comes out below the disc top; check the scale's height_mm");
    const double tilt = std::acos(std::clamp(-pp.up_cam.z(), -1.0, 1.0)) * 180 / M_PI;
    if (tilt > 1.0) g.source_text += ", camera tilted " + fmt("%.1f", tilt) + " deg";
    g.camera = cam;
    return g;
}

} // namespace drape::capture
