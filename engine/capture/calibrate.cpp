#include "engine/capture/calibrate.hpp"
#include "engine/capture/image.hpp"

#include "engine/core/error.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drape::capture {

namespace {

cv::Point3d to_cv(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

void pose_to_cv(const record::Camera& c, cv::Mat& rvec, cv::Mat& tvec)
{
    cv::Matx33d R;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) R(i, j) = c.R(i, j);
    cv::Rodrigues(R, rvec);
    tvec = (cv::Mat_<double>(3, 1) << c.t.x(), c.t.y(), c.t.z());
}

double rms(const record::Camera& c, const std::vector<cv::Point3d>& W, const std::vector<cv::Point2f>& I)
{
    double s = 0;
    for (std::size_t i = 0; i < W.size(); ++i) {
        const Eigen::Vector2d p = c.project({W[i].x, W[i].y, W[i].z});
        s += (p - Eigen::Vector2d(I[i].x, I[i].y)).squaredNorm();
    }
    return W.empty() ? 0.0 : std::sqrt(s / static_cast<double>(W.size()));
}

std::string fmt(const char* f, double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

} // namespace

Calibration calibrate_camera(const record::Record& rec, const std::string& camera, const cv::Mat& image)
{
    auto it = rec.cameras.find(camera);
    if (it == rec.cameras.end()) throw ParameterError("calibrate_camera: no station '" + camera + "' in meta.json");
    Calibration cal;
    cal.declared = cal.measured = it->second;
    const record::Camera& c = cal.declared;

    cv::Mat grey;
    cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
    std::vector<cv::Point3d> W;
    std::vector<cv::Point2f> I;
    for (const record::Board& b : rec.boards) {
        // Crop to the board's declared footprint plus a margin of one square,
        // so the other boards and the fabric cannot confuse the detector.
        std::vector<cv::Point2f> outline;
        for (double fx : {-1.0, b.nx + 1.0})
            for (double fy : {-1.0, b.ny + 1.0}) {
                const Eigen::Vector2d p = c.project({b.x0 + fx * b.square, b.y0 + fy * b.square, b.z});
                if (!std::isfinite(p.x())) continue;
                outline.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()));
            }
        if (outline.size() < 4) {
            cal.boards_missed.push_back(b.name);
            continue;
        }
        cv::Rect roi = cv::boundingRect(outline) & cv::Rect(0, 0, grey.cols, grey.rows);
        if (roi.width < 20 || roi.height < 20) {
            cal.boards_missed.push_back(b.name);
            continue;
        }
        const cv::Size pattern(b.nx - 1, b.ny - 1);
        std::vector<cv::Point2f> corners;
        const cv::Mat crop = grey(roi);
        bool found = cv::findChessboardCorners(crop, pattern, corners,
                                               cv::CALIB_CB_ADAPTIVE_THRESH | cv::CALIB_CB_NORMALIZE_IMAGE);
        if (!found) {
            cal.boards_missed.push_back(b.name);
            continue;
        }
        cv::cornerSubPix(crop, corners, cv::Size(5, 5), cv::Size(-1, -1),
                         cv::TermCriteria(cv::TermCriteria::EPS + cv::TermCriteria::COUNT, 40, 0.01));
        for (auto& p : corners) p += cv::Point2f(static_cast<float>(roi.x), static_cast<float>(roi.y));
        // The detector's corner order is ambiguous up to flips; pick the world
        // ordering whose declared projection lies closest to the detection.
        const int nu = b.nx - 1, nv = b.ny - 1;
        double best = 1e300;
        std::vector<cv::Point3d> best_w;
        for (int flip = 0; flip < 8; ++flip) {
            const bool transpose = flip & 4;
            const int cols = transpose ? nv : nu; // detector's row length
            if (static_cast<int>(corners.size()) != nu * nv) break;
            std::vector<cv::Point3d> w;
            double d = 0;
            for (int k = 0; k < nu * nv; ++k) {
                int a = k % cols, bb = k / cols;
                int i = transpose ? bb : a, j = transpose ? a : bb;
                if (flip & 1) i = nu - 1 - i;
                if (flip & 2) j = nv - 1 - j;
                if (i < 0 || i >= nu || j < 0 || j >= nv) {
                    d = 1e300;
                    break;
                }
                const Eigen::Vector3d X(b.x0 + (i + 1) * b.square, b.y0 + (j + 1) * b.square, b.z);
                w.push_back(to_cv(X));
                const Eigen::Vector2d p = c.project(X);
                d += std::hypot(p.x() - corners[k].x, p.y() - corners[k].y);
            }
            if (d < best) {
                best = d;
                best_w = w;
            }
        }
        if (best_w.empty()) {
            cal.boards_missed.push_back(b.name);
            continue;
        }
        cal.boards_found.push_back(b.name);
        W.insert(W.end(), best_w.begin(), best_w.end());
        I.insert(I.end(), corners.begin(), corners.end());
    }
    cal.corners = static_cast<int>(W.size());
    cal.rms_px_declared = rms(c, W, I);
    if (W.size() < 6) {
        cal.warnings.push_back(camera + ": no chessboard detected; the declared pose is used unchecked");
        return cal;
    }
    cv::Mat rvec, tvec;
    pose_to_cv(c, rvec, tvec);
    cv::solvePnP(W, I, camera_matrix(c), c.dist.empty() ? cv::Mat() : cv::Mat(c.dist), rvec, tvec, true, cv::SOLVEPNP_ITERATIVE);
    cv::Matx33d Rm;
    cv::Rodrigues(rvec, Rm);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) cal.measured.R(i, j) = Rm(i, j);
    cal.measured.t = Eigen::Vector3d(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
    cal.ok = true;
    cal.rms_px_measured = rms(cal.measured, W, I);
    const Eigen::Matrix3d dR = cal.measured.R * c.R.transpose();
    cal.rotation_diff_deg = std::acos(std::clamp((dR.trace() - 1.0) / 2.0, -1.0, 1.0)) * 180.0 / M_PI;
    cal.centre_diff_m = (cal.measured.centre() - c.centre()).norm();
    for (double z : {0.0, -0.15})
        for (int k = 0; k < 72; ++k) {
            const double th = 2 * M_PI * k / 72.0;
            const Eigen::Vector3d X(rec.R1 * std::cos(th), rec.R1 * std::sin(th), z);
            cal.max_shift_px = std::max(cal.max_shift_px, (cal.measured.project(X) - c.project(X)).norm());
        }
    if (cal.max_shift_px > 1.0)
        cal.warnings.push_back(camera + ": declared and measured poses disagree (" + fmt("%.1f", cal.max_shift_px) +
                               " px over the specimen, centres " + fmt("%.1f", cal.centre_diff_m * 1e3) +
                               " mm, rotation " + fmt("%.2f", cal.rotation_diff_deg) + " deg); the measured pose is used");
    if (cal.rms_px_measured > 1.0)
        cal.warnings.push_back(camera + ": chessboard reprojection RMS " + fmt("%.2f", cal.rms_px_measured) +
                               " px is high (lens distortion or wrong intrinsics?)");
    return cal;
}

} // namespace drape::capture
