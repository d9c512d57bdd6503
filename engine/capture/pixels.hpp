#pragma once
// Pixel helpers the capture steps share: colour conversion, sampling, robust
// statistics. Internal to engine/capture.
#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <limits>
#include <string>
#include <vector>

namespace drape::capture::detail {

inline constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// printf-style formatting of one number, for messages.
std::string fmt(const char* f, double v);
/// BGR 8-bit -> smoothed CIE L*a*b* float (L 0..100). A small Gaussian removes
/// sensor noise and JPEG blocking; it is symmetric so it does not move an edge.
cv::Mat to_lab(const cv::Mat& bgr);
/// The Lab pixel nearest to px (clamped to the image).
cv::Vec3f sample(const cv::Mat& lab, const Eigen::Vector2d& px);
/// Median (NaN for an empty set).
double median(std::vector<double> v);
/// Bilinear sample of a single-channel float map; outside -> 0.
double bilinear(const cv::Mat& m, double x, double y);

} // namespace drape::capture::detail
