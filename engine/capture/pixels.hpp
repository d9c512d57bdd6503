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
/// How much a BGR 8-bit image's colours vary: the largest of its channels'
/// standard deviations [levels of 255]. A photo of anything has several; a
/// uniform one (a grey card, a lens cap, a blank file) has less than 1.
double colour_spread(const cv::Mat& bgr);
/// Below this colour_spread a photo holds nothing to measure ("no cloth found").
inline constexpr double kMinColourSpread = 1.0;
/// `img` (8-bit, 3 channels) as cv::grabCut can take it. OpenCV's GrabCut
/// (4.6) runs for minutes on large areas of one exact colour - a uniform
/// 480 x 363 px image never finished, two flat halves took 24 s - so where
/// more than half of the pixels equal their right-hand neighbour, a fixed
/// +-1 level dither (seeded: the same answer every time) is added. A photo
/// with sensor noise is returned as it is (tst_photo's scenes, downscaled to
/// 480 px: at most 0.29 of their pixels equal their neighbour). Not for the
/// segmentation's smoothed Lab image, whose quantised levels are mostly equal
/// neighbours on any photo.
cv::Mat grabcut_input(const cv::Mat& img);
/// A binary mask (CV_8U) with the holes inside its regions filled: only the
/// regions' outer outlines count.
cv::Mat fill_holes(const cv::Mat& mask);

} // namespace drape::capture::detail
