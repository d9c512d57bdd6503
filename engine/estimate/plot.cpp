#include "engine/estimate/plot.hpp"

#include "engine/core/error.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace drape::estimate {

Plot::Plot(int width, int height, std::string title, std::string xlabel, std::string ylabel)
    : m_w(width), m_h(height), m_title(std::move(title)), m_xlabel(std::move(xlabel)), m_ylabel(std::move(ylabel))
{
}

void Plot::line(std::vector<double> x, std::vector<double> y, Rgb c, std::string label, int thickness, bool dashed, bool closed)
{
    Series s{Series::Line, std::move(x), std::move(y), c, std::move(label)};
    s.thickness = thickness;
    s.dashed = dashed;
    s.closed = closed;
    m_series.push_back(std::move(s));
}

void Plot::points(std::vector<double> x, std::vector<double> y, Rgb c, std::string label, int radius)
{
    Series s{Series::Points, std::move(x), std::move(y), c, std::move(label)};
    s.thickness = radius;
    m_series.push_back(std::move(s));
}

void Plot::bars(std::vector<double> x, std::vector<double> y, double w, Rgb c, std::string label)
{
    Series s{Series::Bars, std::move(x), std::move(y), c, std::move(label)};
    s.w = w;
    m_series.push_back(std::move(s));
}

void Plot::interval(double x0, double xc, double x1, double y, Rgb c)
{
    m_series.push_back(Series{Series::Interval, {x0, xc, x1}, {y}, c, ""});
}

void Plot::hline(double y, Rgb c, bool dashed)
{
    Series s{Series::HLine, {}, {y}, c, ""};
    s.dashed = dashed;
    s.thickness = 1;
    m_series.push_back(std::move(s));
}

void Plot::text(double x, double y, std::string str, Rgb c) { m_series.push_back(Series{Series::Text, {x}, {y}, c, std::move(str)}); }

namespace {
cv::Scalar bgr(Rgb c) { return cv::Scalar(c[2], c[1], c[0]); }

double nice_step(double range, int target)
{
    const double raw = range / std::max(1, target);
    const double p = std::pow(10.0, std::floor(std::log10(raw)));
    for (double m : {1.0, 2.0, 2.5, 5.0, 10.0})
        if (m * p >= raw) return m * p;
    return 10 * p;
}

std::string tick_label(double v, double step)
{
    char buf[32];
    // Enough decimals to print every multiple of the step exactly (2.5 -> 1 decimal).
    int dec = std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
    while (dec < 6) {
        const double s = step * std::pow(10.0, dec);
        if (std::abs(s - std::round(s)) < 1e-6 * std::max(1.0, s)) break;
        ++dec;
    }
    std::snprintf(buf, sizeof buf, "%.*f", std::min(dec, 6), std::abs(v) < step * 1e-6 ? 0.0 : v);
    return buf;
}

void dashed_line(cv::Mat& img, cv::Point2d a, cv::Point2d b, cv::Scalar c, int t)
{
    const double len = cv::norm(b - a);
    const int n = std::max(1, static_cast<int>(len / 6));
    for (int i = 0; i < n; i += 2) {
        const cv::Point2d p = a + (b - a) * (static_cast<double>(i) / n);
        const cv::Point2d q = a + (b - a) * (std::min(i + 1, n) / static_cast<double>(n));
        cv::line(img, p, q, c, t, cv::LINE_AA);
    }
}
} // namespace

Rgb palette(int i, int n, bool warm)
{
    const double t = n > 1 ? static_cast<double>(i) / (n - 1) : 0.0;
    if (warm) return {static_cast<unsigned char>(200 + 55 * t), static_cast<unsigned char>(120 * (1 - t)), static_cast<unsigned char>(30 + 40 * (1 - t))};
    return {static_cast<unsigned char>(20 + 60 * t), static_cast<unsigned char>(90 + 120 * t), static_cast<unsigned char>(230 - 100 * t)};
}

Rgb category(int i)
{
    static const Rgb c[10] = {{31, 119, 180}, {255, 127, 14}, {44, 160, 44}, {214, 39, 40}, {148, 103, 189},
                              {140, 86, 75},  {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
    return c[((i % 10) + 10) % 10];
}

void Plot::save(const std::string& path) const
{
    cv::Mat img(m_h, m_w, CV_8UC3, cv::Scalar(255, 255, 255));
    // data range
    double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
    for (const auto& s : m_series) {
        for (double v : s.x)
            if (std::isfinite(v)) x0 = std::min(x0, v - s.w), x1 = std::max(x1, v + s.w);
        for (double v : s.y)
            if (std::isfinite(v)) y0 = std::min(y0, v), y1 = std::max(y1, v);
        if (s.kind == Series::Bars) y0 = std::min(y0, 0.0), y1 = std::max(y1, 0.0);
    }
    if (!std::isfinite(x0)) x0 = 0, x1 = 1;
    if (!std::isfinite(y0)) y0 = 0, y1 = 1;
    if (m_fixed_x) x0 = m_x[0], x1 = m_x[1];
    if (m_fixed_y) y0 = m_y[0], y1 = m_y[1];
    if (x1 - x0 < 1e-300) x0 -= 0.5, x1 += 0.5;
    if (y1 - y0 < 1e-300) y0 -= 0.5, y1 += 0.5;
    if (!m_fixed_x) { const double p = 0.04 * (x1 - x0); x0 -= p; x1 += p; }
    if (!m_fixed_y) { const double p = 0.06 * (y1 - y0); y0 -= p; y1 += p; }
    // The left margin holds the longest row label (parameter keys, effect names).
    int L = 80;
    for (const auto& [v, t] : m_ytick_labels) {
        int base = 0;
        L = std::max(L, cv::getTextSize(t, cv::FONT_HERSHEY_SIMPLEX, 0.35, 1, &base).width + 12);
    }
    L = std::min(L, m_w / 3);
    const int R = 20, T = 40, B = m_caption.empty() ? 55 : 80;
    const int pw = m_w - L - R, ph = m_h - T - B;
    if (m_equal) { // same metres per pixel on both axes
        const double sx = (x1 - x0) / pw, sy = (y1 - y0) / ph, s = std::max(sx, sy);
        const double cx = 0.5 * (x0 + x1), cy = 0.5 * (y0 + y1);
        x0 = cx - 0.5 * s * pw, x1 = cx + 0.5 * s * pw, y0 = cy - 0.5 * s * ph, y1 = cy + 0.5 * s * ph;
    }
    auto P = [&](double x, double y) { return cv::Point2d(L + (x - x0) / (x1 - x0) * pw, T + (y1 - y) / (y1 - y0) * ph); };
    const cv::Scalar grid(230, 230, 230), axis(60, 60, 60);
    const double xs = nice_step(x1 - x0, 8), ys = nice_step(y1 - y0, 6);
    for (double v = std::ceil(x0 / xs) * xs; v <= x1 + 1e-12; v += xs) {
        cv::line(img, P(v, y0), P(v, y1), grid, 1);
        const std::string t = tick_label(v, xs);
        cv::putText(img, t, P(v, y0) + cv::Point2d(-4.0 * t.size(), 18), cv::FONT_HERSHEY_SIMPLEX, 0.4, axis, 1, cv::LINE_AA);
    }
    if (m_ytick_labels.empty()) {
        for (double v = std::ceil(y0 / ys) * ys; v <= y1 + 1e-12; v += ys) {
            cv::line(img, P(x0, v), P(x1, v), grid, 1);
            const std::string t = tick_label(v, ys);
            cv::putText(img, t, P(x0, v) + cv::Point2d(-8.0 - 7.5 * t.size(), 4), cv::FONT_HERSHEY_SIMPLEX, 0.4, axis, 1, cv::LINE_AA);
        }
    } else {
        for (const auto& [v, t] : m_ytick_labels) {
            cv::line(img, P(x0, v), P(x1, v), grid, 1);
            cv::putText(img, t, cv::Point2d(4, P(x0, v).y + 4), cv::FONT_HERSHEY_SIMPLEX, 0.35, axis, 1, cv::LINE_AA);
        }
    }
    cv::rectangle(img, P(x0, y1), P(x1, y0), axis, 1);
    cv::putText(img, m_title, cv::Point(L, 25), cv::FONT_HERSHEY_SIMPLEX, 0.55, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, m_xlabel, cv::Point(L + pw / 2 - 4 * static_cast<int>(m_xlabel.size()), T + ph + 40), cv::FONT_HERSHEY_SIMPLEX, 0.45, axis, 1,
                cv::LINE_AA);
    if (!m_caption.empty())
        cv::putText(img, m_caption, cv::Point(10, m_h - 12), cv::FONT_HERSHEY_SIMPLEX, 0.38, cv::Scalar(80, 80, 80), 1, cv::LINE_AA);
    {
        cv::Mat lab(20, std::max(10, 10 * static_cast<int>(m_ylabel.size())), CV_8UC3, cv::Scalar(255, 255, 255));
        cv::putText(lab, m_ylabel, cv::Point(2, 15), cv::FONT_HERSHEY_SIMPLEX, 0.45, axis, 1, cv::LINE_AA);
        cv::Mat rot;
        cv::rotate(lab, rot, cv::ROTATE_90_COUNTERCLOCKWISE);
        const int y = std::max(0, T + ph / 2 - rot.rows / 2);
        if (y + rot.rows <= img.rows && m_ytick_labels.empty()) rot.copyTo(img(cv::Rect(2, y, rot.cols, rot.rows)));
    }
    img(cv::Rect(0, 0, m_w, m_h)).copyTo(img);
    cv::Mat plot = img(cv::Rect(L, T, pw + 1, ph + 1));
    (void)plot;
    int legend_y = T + 16;
    for (const auto& s : m_series) {
        const cv::Scalar c = bgr(s.colour);
        switch (s.kind) {
        case Series::Line: {
            std::vector<cv::Point2d> pts;
            const std::size_t n = std::min(s.x.size(), s.y.size());
            auto flush = [&] {
                for (std::size_t i = 1; i < pts.size(); ++i)
                    s.dashed ? dashed_line(img, pts[i - 1], pts[i], c, s.thickness) : (void)cv::line(img, pts[i - 1], pts[i], c, s.thickness, cv::LINE_AA);
            };
            for (std::size_t i = 0; i < n; ++i) {
                if (!std::isfinite(s.x[i]) || !std::isfinite(s.y[i])) { flush(); pts.clear(); continue; }
                pts.push_back(P(s.x[i], s.y[i]));
            }
            if (s.closed && pts.size() > 2 && n == pts.size()) pts.push_back(pts.front());
            flush();
            break;
        }
        case Series::Points:
            for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
                if (std::isfinite(s.x[i]) && std::isfinite(s.y[i])) cv::circle(img, P(s.x[i], s.y[i]), s.thickness, c, cv::FILLED, cv::LINE_AA);
            break;
        case Series::Bars:
            for (std::size_t i = 0; i < std::min(s.x.size(), s.y.size()); ++i)
                if (std::isfinite(s.y[i])) cv::rectangle(img, P(s.x[i] - s.w, s.y[i]), P(s.x[i] + s.w, std::clamp(0.0, y0, y1)), c, cv::FILLED);
            break;
        case Series::Interval: {
            const double y = s.y[0];
            cv::line(img, P(s.x[0], y), P(s.x[2], y), c, 3, cv::LINE_AA);
            cv::line(img, P(s.x[0], y) + cv::Point2d(0, -6), P(s.x[0], y) + cv::Point2d(0, 6), c, 2);
            cv::line(img, P(s.x[2], y) + cv::Point2d(0, -6), P(s.x[2], y) + cv::Point2d(0, 6), c, 2);
            cv::circle(img, P(s.x[1], y), 5, cv::Scalar(0, 0, 0), cv::FILLED, cv::LINE_AA);
            break;
        }
        case Series::HLine:
            dashed_line(img, P(x0, s.y[0]), P(x1, s.y[0]), c, 1);
            break;
        case Series::Text:
            cv::putText(img, s.label, P(s.x[0], s.y[0]), cv::FONT_HERSHEY_SIMPLEX, 0.4, c, 1, cv::LINE_AA);
            break;
        }
        if (!s.label.empty() && s.kind != Series::Text) {
            const int lx = L + pw - 190;
            cv::rectangle(img, cv::Point(lx - 4, legend_y - 11), cv::Point(L + pw - 2, legend_y + 5), cv::Scalar(255, 255, 255), cv::FILLED);
            if (s.dashed) dashed_line(img, cv::Point2d(lx, legend_y - 3), cv::Point2d(lx + 24, legend_y - 3), c, 2);
            else cv::line(img, cv::Point(lx, legend_y - 3), cv::Point(lx + 24, legend_y - 3), c, 3);
            cv::putText(img, s.label, cv::Point(lx + 30, legend_y + 1), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(30, 30, 30), 1, cv::LINE_AA);
            legend_y += 16;
        }
    }
    if (!cv::imwrite(path, img)) throw FileError(path + ": cannot write the PNG");
}

} // namespace drape::estimate
