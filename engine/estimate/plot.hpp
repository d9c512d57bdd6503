#pragma once
// A small line/bar plotter for the report PNGs (OpenCV drawing; no Qt in the
// core). Data in any units; the plot maps them to pixels.
#include <array>
#include <string>
#include <vector>

namespace drape::estimate {

using Rgb = std::array<unsigned char, 3>;

class Plot {
public:
    Plot(int width, int height, std::string title, std::string xlabel, std::string ylabel);
    void line(std::vector<double> x, std::vector<double> y, Rgb colour, std::string label = "", int thickness = 2, bool dashed = false,
              bool closed = false);
    void points(std::vector<double> x, std::vector<double> y, Rgb colour, std::string label = "", int radius = 3);
    /// Vertical bars centred at x with half-width w.
    void bars(std::vector<double> x, std::vector<double> y, double w, Rgb colour, std::string label = "");
    /// Horizontal error bar from x0 to x1 at height y, with a dot at xc.
    void interval(double x0, double xc, double x1, double y, Rgb colour);
    void hline(double y, Rgb colour, bool dashed = true);
    void text(double x, double y, std::string s, Rgb colour);
    void equal_aspect(bool on = true) { m_equal = on; }
    void set_xrange(double lo, double hi) { m_x = {lo, hi}; m_fixed_x = true; }
    void set_yrange(double lo, double hi) { m_y = {lo, hi}; m_fixed_y = true; }
    void set_yticklabels(std::vector<std::pair<double, std::string>> t) { m_ytick_labels = std::move(t); }
    void set_caption(std::string c) { m_caption = std::move(c); }
    /// Renders and writes a PNG. Throws FileError when it cannot be written.
    void save(const std::string& path) const;

private:
    struct Series {
        enum Kind { Line, Points, Bars, Interval, HLine, Text } kind;
        std::vector<double> x, y;
        Rgb colour;
        std::string label;
        int thickness = 2;
        bool dashed = false, closed = false;
        double w = 0;
    };
    int m_w, m_h;
    std::string m_title, m_xlabel, m_ylabel, m_caption;
    std::vector<Series> m_series;
    std::array<double, 2> m_x{0, 1}, m_y{0, 1};
    bool m_fixed_x = false, m_fixed_y = false, m_equal = false;
    std::vector<std::pair<double, std::string>> m_ytick_labels;
};

/// Ramp colours for series i of n (blue -> green, or red -> orange when `warm`).
Rgb palette(int i, int n, bool warm = false);
/// Categorical colours (Tableau 10) for unrelated series.
Rgb category(int i);

} // namespace drape::estimate
