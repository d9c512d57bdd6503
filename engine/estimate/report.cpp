#include "engine/estimate/report.hpp"

#include "engine/estimate/plot.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/fabric/preset.hpp"

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <numbers>
#include <sstream>

namespace drape::estimate {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr double kPi = std::numbers::pi;

std::string fmt(const char* f, double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, f, v);
    return buf;
}

std::string safe(const std::string& id)
{
    std::string s = id;
    for (char& c : s)
        if (!(std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_')) c = '_';
    return s;
}

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

/// Rotation [rad] that best lines the simulated folds up with the measured
/// ones at the deepest common depth (fold positions are random, so the plots
/// compare shapes after this rotation; the fit itself never uses phases).
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

/// The candidate effects (issue 20): each one's sqrt(delta chi2) - its |z| for
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

std::string num(double v, const char* f = "%.3g") { return std::isfinite(v) ? fmt(f, v) : std::string("n/a"); }

/// A candidate's fitted amplitude: one number, or "x, y" for the two-column effects.
std::string amplitudes(const EffectCandidate& c)
{
    if (c.amplitudes.size() < 2) return num(c.amplitude);
    std::string s;
    for (double a : c.amplitudes) s += (s.empty() ? "" : ", ") + num(a);
    return s;
}

} // namespace

std::string parameter_table_markdown(const FitResult& r)
{
    std::ostringstream o;
    o << "| parameter | unit | role | value | 95 % interval | constrained | note |\n|---|---|---|---|---|---|---|\n";
    for (const auto& e : r.estimates) {
        o << "| " << e.key << " | " << e.unit << " | " << e.role << " | " << num(e.value) << " | ";
        if (e.role == "fitted") o << num(e.lower95) << " .. " << num(e.upper95);
        else o << "-";
        o << " | " << (e.constrained ? "yes" : "**no**") << " | " << e.note << " |\n";
    }
    return o.str();
}

std::vector<std::string> write_fit_report(const FitResult& r, const std::string& dir, const std::string& preset_path)
{
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw FileError(dir + ": cannot create the report folder (" + ec.message() + ")");
    std::vector<std::string> files;
    const fs::path root(dir);
    std::ostringstream md;
    md << "# Fit report: " << r.name << "\n\n";
    md << "Model `" << to_string(r.options.model) << "`, grid " << r.options.grid << ", seed " << r.options.seed << ", "
       << r.options.seeds_per_evaluation << " perturbation seeds per evaluation. " << r.evaluations << " evaluations, "
       << r.simulations << " simulations, " << num(r.seconds_per_simulation, "%.2f") << " s per simulation, "
       << num(r.wall_seconds, "%.0f") << " s in all" << (r.cancelled ? " (**cancelled**: best point so far)" : "") << ".\n\n";
    if (r.refinement.from_grid > 0)
        md << "**Grid refinement**: " << r.refinement.reason
           << ". The evaluation and time counts above include both fits.\n\n";
    if (r.anisotropy.assessed && !r.anisotropy.reason.empty()) md << "**Warp/weft bending**: " << r.anisotropy.reason << ".\n\n";
    if (r.shear_hold.assessed && !r.shear_hold.reason.empty()) md << "**Shear**: " << r.shear_hold.reason << ".\n\n";
    if (r.flat_calibration.tried) md << "**The preset draped from flat**: " << r.flat_calibration.reason << ".\n\n";
    if (r.grid_bound)
        md << "**Grid-bound preset**: a fitted bending's bending length is below the mesh spacing of the fit's grid, so the "
              "coarse mesh does part of the bending's work and the preset holds at this mesh density only (`drape predict` keeps "
              "it); fit with a finer `--grid` for a preset that carries over (see the notes in the table).\n\n";
    if (!preset_path.empty()) md << "Preset: `" << preset_path << "`.\n\n";
    md << "## Parameters\n\n" << parameter_table_markdown(r) << "\n";
    parameter_plot(r, (root / "parameters.png").string());
    files.push_back("parameters.png");
    md << "![parameters](parameters.png)\n\n";
    const int n = static_cast<int>(r.variables.size());
    if (n > 1 && r.correlation.size()) {
        md << "Correlations of the fitted (log) parameters:\n\n|   |";
        for (const auto& v : r.variables) md << " " << v.name << " |";
        md << "\n|---|";
        for (int i = 0; i < n; ++i) md << "---|";
        md << "\n";
        for (int i = 0; i < n; ++i) {
            md << "| " << r.variables[i].name << " |";
            for (int k = 0; k < n; ++k) md << " " << num(r.correlation(i, k), "%.2f") << " |";
            md << "\n";
        }
        md << "\n";
    }
    md << "## Records\n\n| record | D1/D2 [mm] | D measured [%] | D fitted [%] | D error | nodes measured | nodes fitted | node error |\n"
          "|---|---|---|---|---|---|---|---|\n";
    for (const auto& rf : r.records)
        md << "| " << rf.measured.id << " | " << num(rf.measured.sample_diameter * 1e3, "%.0f") << "/"
           << num(rf.measured.disc_diameter * 1e3, "%.0f") << " | " << num(rf.measured_features.drape_coefficient_percent, "%.1f")
           << " | " << num(rf.simulated_features.drape_coefficient_percent, "%.1f") << " | " << num(rf.dc_error_percent, "%+.1f")
           << " | " << num(rf.measured_features.node_count, "%.0f") << " | " << num(rf.simulated_features.node_count, "%.1f") << " | "
           << num(rf.node_error, "%+.1f") << " |\n";
    md << "\nMeasured node counts: " << (r.records.empty() ? "" : r.records.front().measured.node_source)
       << "; fitted: the same detector on the simulated drape (mean over the seeds).";
    bool on_branch = false;
    for (const auto& rf : r.records) on_branch = on_branch || rf.branch_folds > 0;
    if (on_branch)
        md << " The fit's cold drapes start on each record's measured fold branch (an n-fold lift of "
           << num(r.options.branch_lift_m * 1e3, "%.0f")
           << " mm, n = the measured node count; `--branch measured`), so D and the contours are compared between drapes with the "
              "record's number of folds; the node error says whether that branch holds at the fitted parameters.";
    md << "\n\n";
    bool moved = false;
    for (const auto& rf : r.records) moved = moved || rf.preset_moved;
    if (moved) {
        // The rows above are the contours' optimum's; the saved preset was moved by
        // the calibration from flat: its own drapes, started as the fit's.
        md << "The preset as saved (calibrated from flat, above: "
           << (r.flat_calibration.fold_search ? "moved along the contours' profile and its bendings " : "its bendings ")
           << num(r.flat_calibration.scale, "%.3f") << " x the optimum's) draped as the fit drapes (warm from the optimum's rest states, the fit's seeds"
           << (on_branch ? ", which started on the record's fold branch" : "") << "), the fitted terms' chi2 "
           << num(r.flat_calibration.chi2_preset, "%.1f") << " against the optimum's " << num(r.chi2, "%.1f") << ":\n\n"
           << "| record | D preset [%] | D error | nodes preset | node error |\n|---|---|---|---|---|\n";
        for (const auto& rf : r.records)
            md << "| " << rf.measured.id << " | " << num(rf.preset_features.drape_coefficient_percent, "%.1f")
               << (rf.preset_converged ? "" : " (not at rest)") << " | " << num(rf.preset_dc_error_percent, "%+.1f") << " | "
               << num(rf.preset_features.node_count, "%.1f") << " | " << num(rf.preset_node_error, "%+.1f") << " |\n";
        md << "\n";
    }
    if (!r.records.empty() && r.records.front().cold_seeds > 0) {
        md << "The fit's simulations start from the rest state of the best point so far (warm)"
           << (on_branch ? " or on the measured fold branch" : "")
           << ". Draped from flat with the random mix of modes, as `drape predict`, `drape compare` and the widget drape it (mean of "
           << r.records.front().cold_seeds << " perturbation seeds"
           << (r.options.laying_load < 1 ? ", laid under " + num(r.options.laying_load, "%.2f") +
                                               " g first as the records' lab is assumed to lay them (`--laying`, written into the preset)"
                                         : std::string(", the whole load at once"))
           << ", the flat start's waviness " << num(r.options.perturbation_m * 1e3, "%.1f") << " mm (`--perturbation`, written into the preset)"
           << "), the preset"
           << (r.flat_calibration.applied ? (r.flat_calibration.fold_search ? " (moved along the contours' profile and its bendings " : " (its bendings ") +
                                                num(r.flat_calibration.scale, "%.3f") + " x the contours' optimum: calibrated from flat, above)"
                                          : std::string())
           << " gives"
           << (on_branch ? " (the fold count a random start picks can differ from the record's: a bifurcation, not a misfit)" : "")
           << ":\n\n"
           << "| record | D cold [%] | D error cold | nodes cold | node error cold |";
        // The first seed again on a finer grid (FitOptions::flat_check_grid): does
        // the preset carry over to a CAD's finer mesh?
        int fine = 0;
        double fine_diameter = 0;
        for (const auto& rf : r.records)
            if (rf.cold_fine_grid > fine) {
                fine = rf.cold_fine_grid;
                fine_diameter = rf.measured.sample_diameter;
            }
        if (fine > 0) md << " D at grid " << fine << " [%] | D error | nodes | node error |";
        md << "\n|---|---|---|---|---|" << (fine > 0 ? "---|---|---|---|" : "") << "\n";
        for (const auto& rf : r.records) {
            md << "| " << rf.measured.id << " | " << num(rf.cold_features.drape_coefficient_percent, "%.1f") << " | "
               << num(rf.cold_dc_error_percent, "%+.1f") << " | " << num(rf.cold_features.node_count, "%.1f") << " | "
               << num(rf.cold_node_error, "%+.1f") << " |";
            if (fine > 0) {
                if (rf.cold_fine_grid > 0)
                    md << " " << num(rf.cold_fine_features.drape_coefficient_percent, "%.1f") << (rf.cold_fine_converged ? "" : " (not at rest)")
                       << " | " << num(rf.cold_fine_dc_error_percent, "%+.1f") << " | " << num(rf.cold_fine_features.node_count, "%.0f") << " | "
                       << num(rf.cold_fine_node_error, "%+.0f") << " |";
                else
                    md << " - | - | - | - |";
            }
            md << "\n";
        }
        if (fine > 0)
            md << "\nAt grid " << fine << " the first seed (grid " << r.options.grid
               << " cells are " << num(fine_diameter * 1e3 / std::max(1, r.options.grid - 1), "%.1f")
               << " mm, grid " << fine << " " << num(fine_diameter * 1e3 / std::max(1, fine - 1), "%.1f")
               << " mm): a preset that is the fabric, not the fit's mesh, drapes alike on both (`drape simulate --grid " << fine << "`).\n";
        md << "\n";
    }

    json recs = json::array();
    for (int i = 0; i < static_cast<int>(r.records.size()); ++i) {
        const auto& rf = r.records[i];
        const std::string id = safe(rf.measured.id);
        const double rot = best_rotation(rf);
        md << "### " << rf.measured.id << "\n\n";
        if (top_overlay(rf, rot, (root / (id + "_top_overlay.png")).string())) {
            files.push_back(id + "_top_overlay.png");
            md << "![top overlay](" << id << "_top_overlay.png)\n\n";
        }
        if (rf.measured.contours.empty()) {
            md << "No laser contours: fitted from the photos (drape coefficient, nodes, hem height).\n\n";
        } else {
            outline_plot(rf, rot, (root / (id + "_contours.png")).string());
            r_theta_plot(rf, rot, (root / (id + "_r_theta.png")).string());
            harmonic_plot(r, i, (root / (id + "_harmonics.png")).string());
            files.insert(files.end(), {id + "_contours.png", id + "_r_theta.png", id + "_harmonics.png"});
            md << "![contours](" << id << "_contours.png)\n\n![r(theta)](" << id << "_r_theta.png)\n\n![harmonics](" << id
               << "_harmonics.png)\n\n";
        }
        if (!rf.measured_features.contours.empty())
            md << "| depth [mm] | mean r measured / fitted [mm] | RMS fold amplitude measured / fitted [mm] | nodes measured / fitted |\n|---|---|---|---|\n";
        json depths = json::array();
        for (std::size_t d = 0; d < rf.measured_features.contours.size(); ++d) {
            const auto& m = rf.measured_features.contours[d];
            const auto& s = rf.simulated_features.contours[d];
            md << "| " << num(m.depth_m * 1e3, "%.0f") << " | " << num(m.mean_radius_m * 1e3, "%.1f") << " / "
               << num(s.mean_radius_m * 1e3, "%.1f") << " | " << num(m.fold_rms_m * 1e3, "%.2f") << " / " << num(s.fold_rms_m * 1e3, "%.2f")
               << " | " << m.node_count << " / " << s.node_count << " |\n";
            depths.push_back({{"depth_m", m.depth_m},
                              {"measured_mean_radius_m", m.mean_radius_m},
                              {"fitted_mean_radius_m", s.mean_radius_m},
                              {"measured_fold_rms_m", m.fold_rms_m},
                              {"fitted_fold_rms_m", s.fold_rms_m},
                              {"measured_harmonic_magnitudes_m", m.magnitudes_m},
                              {"fitted_harmonic_magnitudes_m", s.magnitudes_m}});
        }
        md << "\n";
        json dsens = json::object();
        if (!rf.d_drape_per_10_percent.empty()) {
            md << "Sensitivity of D at the optimum (exact, from the rest state's Hessian): D change for +10 % of each "
                  "fitted parameter.\n\n| parameter | value | D change [points] |\n|---|---|---|\n";
            for (const auto& [q, d] : rf.d_drape_per_10_percent) {
                const auto& sp = cloth::spec(q);
                md << "| " << sp.key << " | " << num(r.params[q], "%.3g") << " " << sp.unit << " | " << num(d, "%+.2f") << " |\n";
                dsens[std::string(sp.key)] = d;
            }
            md << "\n";
        }
        recs.push_back({{"id", rf.measured.id},
                        {"rotation_for_plots_deg", rot * 180 / kPi},
                        {"depths", depths},
                        {"d_drape_coefficient_per_10_percent", dsens}});
    }

    const ResidualAnalysis& a = r.residual;
    if (!r.trace.empty()) {
        md << "## Convergence\n\nMethod `" << to_string(r.options.method) << "`: " << r.evaluations << " evaluations ("
           << r.simulations << " drapes), " << r.factorisations << " Hessian factorisations and " << r.back_substitutions
           << " back-substitutions for exact sensitivities, " << r.jacobians << " Jacobians"
           << (r.jacobian_jumps > 0 ? " (" + std::to_string(r.jacobian_jumps) +
                                          " of their entries left at 0: the feature jumped between the difference's points, its slopes at the step and at half "
                                          "of it disagreeing)"
                                    : std::string())
           << ".\n\n";
        convergence_plot(r, (root / "convergence.png").string());
        files.push_back("convergence.png");
        md << "![convergence](convergence.png)\n\n| evaluation | stage | chi2 | best so far | coordinates (";
        for (std::size_t i = 0; i < r.variables.size(); ++i) md << (i ? ", " : "") << (r.variables[i].log_scale ? "log10 " : "") << r.variables[i].name;
        md << ") | time [s] |\n|---|---|---|---|---|---|\n";
        for (const auto& t : r.trace) {
            md << "| " << t.evaluation << " | " << t.stage << " | " << num(t.chi2, "%.1f") << " | " << num(t.best_chi2, "%.1f") << " | ";
            for (std::size_t i = 0; i < t.coords.size(); ++i) md << (i ? ", " : "") << num(t.coords[i], "%.3f");
            md << " | " << num(t.elapsed_s, "%.1f") << " |\n";
        }
        md << "\n";
    }
    md << "## Residual analysis\n\n";
    if (r.residual.candidates.empty() && !r.residual.unexplained.empty()) md << "Candidate effects: " << r.residual.unexplained << ".\n\n";
    if (!r.residual.candidates.empty()) {
        md << "### Candidate effects (engine-made signatures, docs/model-discrepancy.md)\n\n";
        md << (r.residual.named_effect.empty() ? std::string("Named effect: **none**") : "Named effect: **" + r.residual.named_effect + "**");
        if (!r.residual.unexplained.empty()) md << " (" << r.residual.unexplained << ")";
        md << ".\n\n";
        candidates_plot(r, (root / "candidates.png").string());
        files.push_back("candidates.png");
        md << "![candidate effects](candidates.png)\n\n";
        md << "| effect | family | parameters | z | delta chi2 | information | amplitude | verdict | note |\n|---|---|---|---|---|---|---|---|---|\n";
        for (const auto& c : r.residual.candidates) {
            md << "| " << c.name << " | " << c.family << " | " << c.parameters << " | ";
            if (c.verdict == "not testable") md << "- | - | - | - | ";
            else
                md << num(c.z, "%+.2f") << " | " << num(c.delta_chi2, "%.2f") << " | " << num(c.information, "%+.2f") << " | "
                   << amplitudes(c) << " " << c.amplitude_unit << " | ";
            md << c.verdict << " | " << c.note << " |\n";
        }
        md << "\n";
    }
    md << "chi2 = " << num(a.chi2, "%.1f") << " for " << a.dof << " degrees of freedom (RMS whitened residual "
       << num(a.rms_whitened, "%.2f") << "; 1 = at the noise): the residual **" << (a.exceeds_noise ? "exceeds" : "is within")
       << "** the measurement noise. RMS contour residual " << num(a.rms_m * 1e3, "%.2f") << " mm.\n\n";
    if (!a.exceeds_because.empty()) {
        md << "Beyond noise by (each test at about 3 sigma of its own statistic):";
        for (const auto& b : a.exceeds_because) md << "\n- " << b;
        md << "\n\n";
    }
    for (const auto& [k, z] : a.signature_z)
        md << "Matched filter `" << k << "`: z = " << num(z, "%.2f") << " (above 3: the residual has that effect's shape).\n\n";
    md << "| channel | whitened RMS |\n|---|---|\n";
    for (const auto& [k, v] : a.kind_rms) md << "| " << k << " | " << num(v, "%.2f") << " |\n";
    md << "\nDominant harmonics (whitened RMS > 2): ";
    if (a.dominant_harmonics.empty()) md << "none";
    for (int k : a.dominant_harmonics) md << k << " ";
    md << "\n\n";
    if (a.candidate_effects.empty()) md << "No candidate effect: the model explains the record(s) to the noise level"
                                        << (a.exceeds_noise ? " as far as the signatures checked can tell" : "") << ".\n";
    for (std::size_t i = 0; i < a.candidate_effects.size(); ++i) md << "- **" << a.candidate_effects[i] << "**: " << a.evidence[i] << "\n";
    md << "\nNoise model (1 sigma): laser " << num(r.options.noise.laser_m * 1e3, "%.2f") << " mm per point, D "
       << num(r.options.noise.dc_lab_percent, "%.1f") << " % (drapemeter) + " << num(r.options.noise.dc_seed_percent, "%.1f")
       << " % (drape-to-drape), nodes " << num(r.options.noise.nodes, "%.2f") << ", contour mean radius "
       << num(r.options.noise.radius_seed_m * 1e3, "%.1f") << " mm, fold amplitude / harmonic magnitudes "
       << num(r.options.noise.fold_seed_m * 1e3, "%.1f") << " mm (defaults; each term's sigma is then multiplied by sqrt(1 + 1/seeds), contour floors by sqrt(depths), and raised to the drape-to-drape spread measured at the optimum: see the `sigma` of each term in report.json and docs/estimate.md).\n";

    json rep = fit_to_json(r);
    rep["records_detail"] = recs;
    json terms = json::array();
    for (const auto& t : r.residuals)
        terms.push_back({{"record", t.record}, {"kind", t.kind}, {"depth_m", t.depth_m}, {"harmonic", t.harmonic}, {"simulated", t.simulated},
                         {"measured", t.measured}, {"sigma", t.sigma}, {"whitened", t.whitened()}, {"fitted", t.fitted}});
    rep["residual_terms"] = terms;
    drape::write_file_atomic((root / "report.json").string(), rep.dump(2) + "\n");
    drape::write_file_atomic((root / "report.md").string(), md.str());
    files.push_back("report.json");
    files.push_back("report.md");
    return files;
}

} // namespace drape::estimate
