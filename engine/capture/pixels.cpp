#include "engine/capture/pixels.hpp"

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drape::capture::detail {

std::string fmt(const char* f, double v)
{
    char buf[96];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

cv::Mat to_lab(const cv::Mat& bgr)
{
    cv::Mat f, lab;
    bgr.convertTo(f, CV_32F, 1.0 / 255.0);
    cv::cvtColor(f, lab, cv::COLOR_BGR2Lab);
    cv::GaussianBlur(lab, lab, cv::Size(0, 0), 1.0);
    return lab;
}

cv::Vec3f sample(const cv::Mat& lab, const Eigen::Vector2d& px)
{
    const int x = std::clamp(static_cast<int>(std::lround(px.x())), 0, lab.cols - 1);
    const int y = std::clamp(static_cast<int>(std::lround(px.y())), 0, lab.rows - 1);
    return lab.at<cv::Vec3f>(y, x);
}

double median(std::vector<double> v)
{
    if (v.empty()) return kNaN;
    auto mid = v.begin() + static_cast<long>(v.size() / 2);
    std::nth_element(v.begin(), mid, v.end());
    return *mid;
}

double bilinear(const cv::Mat& m, double x, double y)
{
    if (!(x >= 0 && y >= 0 && x <= m.cols - 1 && y <= m.rows - 1)) return 0.0;
    const int x0 = std::min(static_cast<int>(x), m.cols - 2), y0 = std::min(static_cast<int>(y), m.rows - 2);
    const double fx = x - x0, fy = y - y0;
    const float* r0 = m.ptr<float>(y0);
    const float* r1 = m.ptr<float>(y0 + 1);
    return (1 - fy) * ((1 - fx) * r0[x0] + fx * r0[x0 + 1]) + fy * ((1 - fx) * r1[x0] + fx * r1[x0 + 1]);
}

double colour_spread(const cv::Mat& bgr)
{
    if (bgr.empty()) return 0;
    cv::Scalar mean, sd;
    cv::meanStdDev(bgr, mean, sd);
    return std::max({sd[0], sd[1], sd[2]});
}

cv::Mat grabcut_input(const cv::Mat& img)
{
    if (img.cols < 2 || img.rows < 1) return img;
    const cv::Rect left(0, 0, img.cols - 1, img.rows), right(1, 0, img.cols - 1, img.rows);
    cv::Mat diff;
    cv::absdiff(img(left), img(right), diff);
    cv::Mat grey;
    cv::transform(diff, grey, cv::Matx13f(1, 1, 1)); // 0 where all three channels are equal
    const double flat = static_cast<double>(left.area() - cv::countNonZero(grey)) / static_cast<double>(left.area());
    if (flat <= 0.5) return img;
    cv::Mat noise(img.size(), CV_16SC3), out;
    cv::RNG rng(12345);
    rng.fill(noise, cv::RNG::UNIFORM, -1, 2); // -1, 0 or +1
    img.convertTo(out, CV_16SC3);
    out += noise;
    out.convertTo(out, CV_8UC3); // saturating: 255 + 1 stays 255, 255 - 1 is 254
    return out;
}

cv::Mat fill_holes(const cv::Mat& mask)
{
    std::vector<std::vector<cv::Point>> cs;
    cv::findContours(mask.clone(), cs, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_NONE);
    cv::Mat filled = cv::Mat::zeros(mask.size(), CV_8U);
    cv::drawContours(filled, cs, -1, cv::Scalar(255), cv::FILLED);
    return filled;
}

} // namespace drape::capture::detail
