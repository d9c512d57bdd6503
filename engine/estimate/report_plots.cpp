// The fit report's plots (write_fit_report, report.cpp): the parameters with
// their intervals, the convergence, the candidate effects and, per record, the
// contours, r(theta), the harmonics and the top photo with the fitted outline.
#include "engine/estimate/detail/report_plots.hpp"

#include "engine/estimate/plot.hpp"

#include "engine/core/error.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace drape::estimate::detail {

namespace {

constexpr double kPi = std::numbers::pi;

/// r at angle theta [rad] of a profile (linear interpolation, NaN-aware).
double sample(const cloth::RadialProfile& p, double theta)
{
    const int n = p.size();
    double t = std::fmod(theta, 2 * kPi);
    if (t < 0) t += 2 * kPi;
    const double u = t / (2 * kPi) * n;
    const int k = static_cast<int>(std::floor(u)) % n;
    const double f = u - std::floor(u);
    return (1 - f) * p.r[k] + f * p.r[(k + 1) % n];
}

void profile_xy(const cloth::RadialProfile& p, double rot, std::vector<double>& x, std::vector<double>& y, double scale = 1e3)
{
    x.clear();
    y.clear();
    for (int k = 0; k < p.size(); ++k) {
        const double t = p.theta(k) + rot;
        x.push_back(p.r[k] * std::cos(t) * scale);
        y.push_back(p.r[k] * std::sin(t) * scale);
    }
}

} // namespace

std::string fmt(const char* f, double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

double best_rotation(const RecordFit& rf)
{
    if (rf.measured.contours.empty() || rf.simulations.empty()) return 0;
    const auto& m = rf.measured.contours.back();
    const cloth::Slice* s = nullptr;
    for (const auto& sl : rf.simulations.front().slices)
        if (std::abs(sl.depth_m - m.depth_m) < 1e-9) s = &sl;
    if (!s) return 0;
    double best = 0, best_err = HUGE_VAL;
    for (int a = 0; a < 360; ++a) {
        const double phi = a * kPi / 180;
        double e = 0;
        int used = 0;
        for (int k = 0; k < m.profile.size(); k += 2) {
            const double rs = sample(s->profile, m.profile.theta(k) - phi);
            if (!std::isfinite(rs)) continue;
            e += (rs - m.profile.r[k]) * (rs - m.profile.r[k]);
            ++used;
        }
        if (used && e / used < best_err) best_err = e / used, best = phi;
    }
    return best;
}

void outline_plot(const RecordFit& rf, double rot, const std::string& path)
{
    Plot pl(640, 680, rf.measured.id + ": contours measured (blue) vs fitted (red)", "x (warp) [mm]", "y (weft) [mm]");
    pl.equal_aspect();
    std::vector<double> x, y;
    const int nd = static_cast<int>(rf.measured.contours.size());
    for (int d = 0; d < nd; ++d) {
        profile_xy(rf.measured.contours[d].profile, 0, x, y);
        pl.line(x, y, palette(d, nd), d == nd - 1 ? "measured contours" : "", 2, false, true);
    }
    if (!rf.simulations.empty()) {
        const auto& sim = rf.simulations.front();
        int d = 0;
        for (const auto& s : sim.slices) {
            profile_xy(s.profile, rot, x, y);
            pl.line(x, y, palette(d, nd, true), d == nd - 1 ? "fitted slices" : "", 1, true, true);
            ++d;
        }
        x.clear();
        y.clear();
        for (const auto& v : sim.outline) {
            const double t = std::atan2(v.y(), v.x()) + rot, r = v.norm();
            x.push_back(r * std::cos(t) * 1e3);
            y.push_back(r * std::sin(t) * 1e3);
        }
        pl.line(x, y, {120, 120, 120}, "fitted shadow outline", 1, true, true);
    }
    x.clear();
    y.clear();
    for (int k = 0; k <= 180; ++k) {
        x.push_back(rf.measured.disc_diameter / 2 * std::cos(k * 2 * kPi / 180) * 1e3);
        y.push_back(rf.measured.disc_diameter / 2 * std::sin(k * 2 * kPi / 180) * 1e3);
    }
    pl.line(x, y, {0, 0, 0}, "support disc", 1);
    const double R = rf.measured.sample_diameter / 2 * 1e3;
    pl.set_xrange(-R, R);
    pl.set_yrange(-R, R);
    pl.set_caption("fitted drape rotated by " + fmt("%.0f", rot * 180 / kPi) +
                   " deg to line up its folds (fold positions are random; the fit compares phase-free features)");
    pl.save(path);
}

bool top_overlay(const RecordFit& rf, double rot, const std::string& path)
{
    if (!rf.measured.top_camera || rf.measured.top_photo.empty()) return false;
    cv::Mat img = cv::imread(rf.measured.top_photo, cv::IMREAD_COLOR);
    if (img.empty()) return false;
    const record::Camera& cam = *rf.measured.top_camera;
    auto draw = [&](const std::vector<Eigen::Vector3d>& pts, cv::Scalar c, int t, bool closed) {
        std::vector<cv::Point> px;
        for (const auto& p : pts) {
            const Eigen::Vector2d u = cam.project(p);
            px.push_back(cv::Point(static_cast<int>(std::lround(u.x())), static_cast<int>(std::lround(u.y()))));
        }
        cv::polylines(img, px, closed, c, t, cv::LINE_AA);
    };
    for (const auto& c : rf.measured.contours) {
        std::vector<Eigen::Vector3d> pts;
        for (int k = 0; k < c.profile.size(); ++k)
            pts.push_back({c.profile.r[k] * std::cos(c.profile.theta(k)), c.profile.r[k] * std::sin(c.profile.theta(k)), -c.depth_m});
        draw(pts, cv::Scalar(255, 160, 0), 1, true);
    }
    if (!rf.simulations.empty()) {
        const auto& sim = rf.simulations.front();
        for (const auto& s : sim.slices) {
            std::vector<Eigen::Vector3d> pts;
            for (int k = 0; k < s.profile.size(); ++k) {
                if (!std::isfinite(s.profile.r[k])) continue;
                const double t = s.profile.theta(k) + rot;
                pts.push_back({s.profile.r[k] * std::cos(t), s.profile.r[k] * std::sin(t), -s.depth_m});
            }
            if (pts.size() > 2) draw(pts, cv::Scalar(40, 40, 230), 1, true);
        }
        std::vector<Eigen::Vector3d> outline;
        const double zmean = sim.hem.mean_z;
        for (const auto& v : sim.outline) {
            const double t = std::atan2(v.y(), v.x()) + rot, r = v.norm();
            outline.push_back({r * std::cos(t), r * std::sin(t), zmean});
        }
        if (outline.size() > 2) draw(outline, cv::Scalar(0, 220, 255), 2, true);
    }
    // Crop to the specimen (its flat radius projected at the pedestal top) and
    // enlarge, so the contours can be told apart.
    {
        const double R = rf.measured.sample_diameter / 2 * 1.1;
        double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
        for (int k = 0; k < 36; ++k) {
            const Eigen::Vector2d u = cam.project({R * std::cos(k * kPi / 18), R * std::sin(k * kPi / 18), 0.0});
            u0 = std::min(u0, u.x()), u1 = std::max(u1, u.x()), v0 = std::min(v0, u.y()), v1 = std::max(v1, u.y());
        }
        const cv::Rect roi = cv::Rect(cv::Point(static_cast<int>(u0), static_cast<int>(v0)), cv::Point(static_cast<int>(u1), static_cast<int>(v1))) &
                             cv::Rect(0, 0, img.cols, img.rows);
        if (roi.area() > 100) {
            cv::Mat crop;
            cv::resize(img(roi), crop, cv::Size(), 2.0, 2.0, cv::INTER_CUBIC);
            cv::Mat canvas(crop.rows + 50, crop.cols, CV_8UC3, cv::Scalar(255, 255, 255));
            crop.copyTo(canvas(cv::Rect(0, 50, crop.cols, crop.rows)));
            img = canvas;
        }
    }
    cv::putText(img, rf.measured.id + ": measured contours (blue), fitted slices (red), fitted shadow outline at mean hem height (yellow)",
                cv::Point(10, 20), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    cv::putText(img, "fitted drape rotated by " + fmt("%.0f", rot * 180 / kPi) + " deg to line up its folds (fold positions are random)",
                cv::Point(10, 40), cv::FONT_HERSHEY_SIMPLEX, 0.4, cv::Scalar(0, 0, 0), 1, cv::LINE_AA);
    if (!cv::imwrite(path, img)) throw FileError(path + ": cannot write the PNG");
    return true;
}

void r_theta_plot(const RecordFit& rf, double rot, const std::string& path)
{
    Plot pl(900, 520, rf.measured.id + ": r(theta) per depth, measured (solid) vs fitted (dashed)", "theta [deg] (0 = warp, 90 = weft)",
            "r [mm]");
    const int nd = static_cast<int>(rf.measured.contours.size());
    for (int d = 0; d < nd; ++d) {
        const auto& c = rf.measured.contours[d];
        std::vector<double> t, r;
        for (int k = 0; k < c.profile.size(); ++k) {
            t.push_back(c.profile.theta(k) * 180 / kPi);
            r.push_back(c.profile.r[k] * 1e3);
        }
        pl.line(t, r, palette(d, nd), d == 0 || d == nd - 1 ? "measured " + fmt("%.0f mm", c.depth_m * 1e3) : "", 2);
        if (!rf.simulations.empty()) {
            for (const auto& s : rf.simulations.front().slices) {
                if (std::abs(s.depth_m - c.depth_m) > 1e-9) continue;
                std::vector<double> ts, rs;
                for (int k = 0; k < 360; ++k) {
                    ts.push_back(k);
                    rs.push_back(sample(s.profile, k * kPi / 180 - rot) * 1e3);
                }
                pl.line(ts, rs, palette(d, nd, true), d == 0 || d == nd - 1 ? "fitted " + fmt("%.0f mm", c.depth_m * 1e3) : "", 1, true);
            }
        }
    }
    pl.set_xrange(0, 360);
    pl.set_caption("depths " + fmt("%.0f", rf.measured.contours.front().depth_m * 1e3) + ".." +
                   fmt("%.0f mm", rf.measured.contours.back().depth_m * 1e3) + " below the pedestal top; fitted rotated by " +
                   fmt("%.0f deg", rot * 180 / kPi));
    pl.save(path);
}

void harmonic_plot(const FitResult& fr, int record, const std::string& path)
{
    const auto& rf = fr.records[record];
    Plot pl(760, 460, rf.measured.id + ": residual per harmonic (fitted - measured) / noise", "harmonic k", "whitened residual");
    const int nd = static_cast<int>(rf.measured.contours.size());
    const double w = 0.8 / std::max(1, nd);
    for (int d = 0; d < nd; ++d) {
        std::vector<double> k, v;
        for (const auto& t : fr.residuals)
            if (t.record == record && (t.kind == "harmonic" || t.kind == "cos1" || t.kind == "sin1") &&
                std::abs(t.depth_m - rf.measured.contours[d].depth_m) < 1e-9) {
                // k = 1: the signed a1 (left half) and b1 (right half) of the slot.
                const double centre = t.kind == "cos1" ? 0.8 : t.kind == "sin1" ? 1.2 : t.harmonic;
                const double width = t.kind == "harmonic" ? 1.0 : 0.5;
                k.push_back(centre - 0.4 * width + width * w * (d + 0.5));
                v.push_back(t.whitened());
            }
        pl.bars(k, v, 0.45 * w, palette(d, nd), d == 0 || d == nd - 1 ? fmt("depth %.0f mm", rf.measured.contours[d].depth_m * 1e3) : "");
    }
    pl.hline(2, {200, 0, 0});
    pl.hline(-2, {200, 0, 0});
    pl.hline(0, {0, 0, 0}, false);
    pl.set_caption("bars: harmonic magnitude |c_k| residual per depth (k = 1: signed a1 left, b1 right); dashed: +-2 sigma");
    pl.save(path);
}

void parameter_plot(const FitResult& fr, const std::string& path)
{
    std::vector<const ParamEstimate*> fitted;
    for (const auto& e : fr.estimates)
        if (e.role == "fitted") fitted.push_back(&e);
    const int n = static_cast<int>(fitted.size());
    Plot pl(820, 130 + 55 * std::max(n, 1), "fitted parameters: 95 % intervals relative to the estimate",
            "decades from the estimate (linear parameters: difference in their unit)", "");
    std::vector<std::pair<double, std::string>> labels;
    for (int i = 0; i < n; ++i) {
        const auto& e = *fitted[i];
        const auto* ps = cloth::find_param(e.key);
        const bool lg = ps ? ps->log_scale : true;
        auto c = [&](double v) { return lg ? std::log10(std::max(v, 1e-300) / e.value) : v - e.value; };
        const Rgb col = e.constrained ? Rgb{30, 140, 60} : Rgb{210, 60, 40};
        const double y = n - i;
        pl.interval(std::max(-1.5, c(e.lower95)), 0.0, std::min(1.5, c(e.upper95)), y, col);
        labels.push_back({y, e.key});
        char buf[160];
        std::snprintf(buf, sizeof buf, "%.3g %s  [%.3g .. %.3g]%s", e.value, e.unit.c_str(), e.lower95, e.upper95,
                      e.constrained ? "" : "  NOT CONSTRAINED");
        pl.text(-1.45, y + 0.25, buf, {40, 40, 40});
    }
    pl.set_xrange(-1.5, 1.5);
    pl.set_yrange(0.3, n + 0.7);
    pl.set_yticklabels(labels);
    pl.set_caption("green: constrained by the data; red: not constrained (interval wider than a decade, or at a fit bound)");
    pl.save(path);
}

/// The candidate effects: each one's sqrt(delta chi2) - its |z| for
/// one parameter - as a bar from 0, against the 3-sigma levels of one and two
/// parameters; red beyond noise, grey within, the named one green, the
/// untestable ones listed with why.
void candidates_plot(const FitResult& fr, const std::string& path)
{
    const auto& cs = fr.residual.candidates;
    const int n = static_cast<int>(cs.size());
    Plot pl(860, 150 + 34 * std::max(n, 1), "candidate effects: how much of the residual each would explain",
            "sqrt(delta chi2) of the refit with the effect freed (= |z| for one parameter)", "");
    double top = 4.5;
    for (const auto& c : cs)
        if (c.verdict != "not testable" && std::isfinite(c.delta_chi2)) // room for the note beside a bar past the 3-sigma line
            top = std::max(top, std::sqrt(c.delta_chi2) * (c.verdict == "within noise" && !c.note.empty() && c.delta_chi2 > 9 ? 1.45 : 1.08));
    std::vector<std::pair<double, std::string>> labels;
    for (int i = 0; i < n; ++i) {
        const auto& c = cs[static_cast<std::size_t>(i)];
        const double y = n - i;
        labels.push_back({y, c.name});
        if (c.verdict == "not testable") {
            std::string why = c.note;
            if (why.size() > 72) why = why.substr(0, why.rfind(' ', 68)) + " ..."; // the table below has it whole
            pl.text(0.02 * top, y - 0.15, "not testable: " + why, {120, 120, 120});
            continue;
        }
        const double v = std::sqrt(std::max(0.0, c.delta_chi2));
        const Rgb col = c.name == fr.residual.named_effect ? Rgb{30, 150, 60} : c.verdict == "beyond noise" ? Rgb{210, 60, 40} : Rgb{150, 150, 150};
        pl.interval(0.0, v, v, y, col);
        if (!c.note.empty() && c.verdict == "within noise" && v > 3) pl.text(v + 0.01 * top, y - 0.15, "amplitude out of range", {120, 120, 120});
    }
    for (double lvl : {3.0, std::sqrt(11.83)}) pl.line({lvl, lvl}, {0.3, n + 0.7}, {90, 90, 90}, "", 1, true);
    pl.set_xrange(0, top);
    pl.set_yrange(0.3, n + 0.7);
    pl.set_yticklabels(labels);
    pl.set_caption(fr.residual.named_effect.empty()
                       ? std::string("named: none. Dashed: 3 sigma for one and for two parameters; red beyond noise, grey within")
                       : "named: " + fr.residual.named_effect + " (green). Dashed: 3 sigma for one and two parameters; red beyond noise, grey within");
    pl.save(path);
}

/// The fit's convergence: chi2 of every evaluation (points, one colour per
/// stage) and the best so far (line), against the evaluation number.
void convergence_plot(const FitResult& fr, const std::string& path)
{
    Plot pl(820, 420, "fit convergence: chi2 of each evaluation and the best so far", "evaluation", "chi2 (fitted terms)");
    std::vector<double> ev, best;
    std::vector<std::string> stages;
    for (const auto& t : fr.trace) {
        ev.push_back(t.evaluation);
        best.push_back(t.best_chi2);
        if (std::find(stages.begin(), stages.end(), t.stage) == stages.end()) stages.push_back(t.stage);
    }
    const Rgb palette[] = {{70, 70, 70}, {30, 110, 200}, {220, 120, 20}, {40, 150, 60}, {200, 50, 50}, {140, 70, 170}, {20, 160, 160}, {150, 120, 40}};
    double top = 0;
    for (const auto& t : fr.trace)
        if (std::isfinite(t.chi2)) top = std::max(top, std::min(t.chi2, 4 * (best.empty() ? t.chi2 : best.back())));
    for (std::size_t k = 0; k < stages.size(); ++k) {
        std::vector<double> x, y;
        for (const auto& t : fr.trace)
            if (t.stage == stages[k] && std::isfinite(t.chi2)) x.push_back(t.evaluation), y.push_back(std::min(t.chi2, top));
        pl.points(x, y, palette[k % 8], stages[k], 4);
    }
    std::vector<double> bx, by;
    for (std::size_t i = 0; i < ev.size(); ++i)
        if (std::isfinite(best[i])) bx.push_back(ev[i]), by.push_back(best[i]);
    pl.line(bx, by, {0, 0, 0}, "best so far", 2);
    if (top > 0) pl.set_yrange(0, top * 1.8); // room above the points for the legend
    pl.set_caption("values above 4x the final best are drawn at that height; the spread stage re-scores with the measured drape-to-drape noise");
    pl.save(path);
}

} // namespace drape::estimate::detail
