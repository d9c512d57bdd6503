// drape fit-summary: tables and plots across fit reports (several records,
// several models), e.g. the before/after of a model change (docs/model-discrepancy.md).
#include "cli/command.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/fabric/preset.hpp"
#include "engine/estimate/objective.hpp"
#include "engine/estimate/plot.hpp"
#include "engine/estimate/residual.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <sstream>

namespace drape::cli {
namespace cmd_fit_summary {

const char* kUsage = R"(usage: drape fit-summary --out DIR LABEL=REPORT_DIR [LABEL=REPORT_DIR ...]

Reads the report.json of `drape fit --report` folders, groups them by LABEL
(e.g. before=..., after=...) and writes to DIR:
  summary.md            per record and label: D and node count measured / fitted, and
                        of the preset draped from flat (the fit's grid and the finer
                        --flat-grid), the calibration from flat, chi2 / dof, the rim
                        matched filter z, candidate effects; per label how many records
                        are within 2 points and 1 node as fitted and from flat
  summary.json          the same numbers
  dc_error.png          fitted - measured D per record, one marker per label
  dc_error_flat.png     the same for the preset draped from flat (the fit's grid; a bar to
                        the finer grid's drape), when the reports have those drapes
  radius_error_LABEL.png, fold_error_LABEL.png
                        contour mean radius / RMS fold amplitude, simulated - measured,
                        against depth, one line per record
The residual analysis is recomputed from each report's residual terms with
this version's rules, so reports written by older versions compare like with like.)";

struct Entry {
    std::string label, dir, id;
    double d_meas = NAN, d_fit = NAN, n_meas = NAN, n_fit = NAN;
    double d_cold = NAN, n_cold = NAN; ///< the preset draped from flat (reports since 2026-11-22)
    double d_fine = NAN, n_fine = NAN; ///< the same on the finer grid (`--flat-grid`, reports since 2026-12-01)
    int fine_grid = 0;
    bool fine_at_rest = true;          ///< cold_fine_converged: a drape the budget stopped is shown, not counted
    double calibration = NAN;          ///< the bendings' scale from flat when applied (fit.flat_calibration)
    bool calibration_profile = false;  ///< ... after a step along the contours' profile (other parameters moved too)
    double waviness_m = NAN;           ///< provenance.perturbation_m of the drapes from flat
    double chi2 = 0;
    int dof = 0;
    double rim_z = 0;
    bool exceeds = false;
    std::vector<std::string> candidates;
    std::vector<std::pair<double, double>> radius, fold; // (depth mm, error mm)
    std::string model;
    bool edge_contact = true;
};

Entry read_report(const std::string& label, const std::string& dir)
{
    const std::string path = (std::filesystem::path(dir) / "report.json").string();
    std::ifstream in(path);
    if (!in) throw FileError(path + ": cannot open (is " + dir + " a `drape fit --report` folder?)");
    nlohmann::json j;
    try {
        in >> j;
    } catch (const std::exception& e) {
        throw FileError(path + ": not valid JSON (" + e.what() + ")");
    }
    if (!j.contains("residual_terms") || !j.contains("fit") || !j.contains("provenance"))
        throw FileError(path + ": missing 'residual_terms', 'fit' or 'provenance' (not a fit report)");
    Entry e;
    e.label = label;
    e.dir = dir;
    const auto& prov = j["provenance"];
    e.model = prov.value("model", "baseline");
    e.edge_contact = prov.value("edge_contact", false); // reports before edge contact existed lack the key
    std::vector<std::string> channels = prov.value("channels", std::vector<std::string>{"dc", "nodes", "hem", "contours"});
    const auto& recs = j["fit"].value("records", nlohmann::json::array());
    if (recs.size() != 1) throw FileError(path + ": fit-summary takes single-record fits (this one has " + std::to_string(recs.size()) + ")");
    const auto& r = recs[0];
    e.id = r.value("id", std::string("?"));
    e.d_meas = r.value("measured_drape_coefficient_percent", NAN);
    e.d_fit = r.value("fitted_drape_coefficient_percent", NAN);
    e.n_meas = r.value("measured_node_count", NAN);
    e.n_fit = r.value("fitted_node_count", NAN);
    if (r.contains("cold_drape_coefficient_percent") && r["cold_drape_coefficient_percent"].is_number()) {
        e.d_cold = r["cold_drape_coefficient_percent"].get<double>();
        e.n_cold = r.value("cold_node_count", NAN);
    }
    if (r.contains("cold_fine_drape_coefficient_percent") && r["cold_fine_drape_coefficient_percent"].is_number()) {
        e.d_fine = r["cold_fine_drape_coefficient_percent"].get<double>();
        e.n_fine = r.value("cold_fine_node_count", NAN);
        e.fine_grid = r.value("cold_fine_grid", 0);
        e.fine_at_rest = r.value("cold_fine_converged", true);
    }
    if (const auto& fj = j["fit"]; fj.contains("flat_calibration") && fj["flat_calibration"].is_object() &&
                                   fj["flat_calibration"].value("applied", false)) {
        e.calibration = fj["flat_calibration"].value("scale", NAN);
        e.calibration_profile = fj["flat_calibration"].value("fold_search", false);
    }
    if (prov.contains("perturbation_m") && prov["perturbation_m"].is_number()) e.waviness_m = prov["perturbation_m"].get<double>();
    int fitted = 0;
    for (const auto& p : j["fit"].value("parameters", nlohmann::json::array()))
        if (p.value("role", "") == "fitted") ++fitted;
    // The measurement model's axis parameters (re-centred or untilted stacks)
    // count too: the fit's own dof says how many (reports since 2026-11-30).
    if (const auto& fj = j["fit"]; fj.contains("dof") && fj["dof"].is_number_integer() && fj.contains("chi2")) {
        int terms_fitted = 0;
        for (const auto& t : j["residual_terms"]) terms_fitted += t.value("fitted", true) ? 1 : 0;
        fitted = std::max(fitted, terms_fitted - fj["dof"].get<int>());
    }
    std::vector<estimate::ResidualTerm> terms;
    for (const auto& t : j["residual_terms"]) {
        estimate::ResidualTerm rt;
        rt.record = t.value("record", 0);
        rt.kind = t.value("kind", "");
        rt.depth_m = t.value("depth_m", 0.0);
        rt.harmonic = t.value("harmonic", 0);
        rt.simulated = t.value("simulated", 0.0);
        rt.measured = t.value("measured", 0.0);
        rt.sigma = t.value("sigma", 1.0);
        rt.smooth = rt.kind != "nodes";
        rt.fitted = t.contains("fitted") ? t["fitted"].get<bool>()
                                         : std::find(channels.begin(), channels.end(), estimate::channel_of(rt.kind)) != channels.end();
        if (!(rt.sigma > 0)) throw FileError(path + ": residual term '" + rt.kind + "' has sigma " + std::to_string(rt.sigma));
        if (rt.kind == "mean_radius") e.radius.push_back({rt.depth_m * 1e3, (rt.simulated - rt.measured) * 1e3});
        if (rt.kind == "fold_rms") e.fold.push_back({rt.depth_m * 1e3, (rt.simulated - rt.measured) * 1e3});
        terms.push_back(rt);
    }
    const estimate::ResidualAnalysis a = estimate::analyse_residual(terms, fitted);
    e.chi2 = a.chi2;
    e.dof = a.dof;
    e.exceeds = a.exceeds_noise;
    e.candidates = a.candidate_effects;
    for (const auto& [k, z] : a.signature_z)
        if (k == "rim_wrapping") e.rim_z = z;
    return e;
}

/// One row per record and fit, in summary.md and summary.json.
nlohmann::json record_rows(std::ostringstream& md, const std::vector<std::string>& ids, const std::vector<std::string>& labels, const std::vector<Entry>& entries)
{
    md << "| record | fit | D meas. [%] | D fit [%] | D err | nodes meas. | nodes fit | D err cold | nodes err cold | D err cold, finer grid | "
          "nodes err cold, finer grid | calibrated from flat | chi2 / dof | rim z | beyond noise | candidate effects |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    nlohmann::json js = nlohmann::json::array();
    char buf[512];
    for (const auto& id : ids)
        for (const auto& l : labels)
            for (const auto& e : entries) {
                if (e.id != id || e.label != l) continue;
                std::string cands;
                for (const auto& c : e.candidates) cands += (cands.empty() ? "" : ", ") + c;
                char cold_d[32] = "-", cold_n[32] = "-";
                if (std::isfinite(e.d_cold)) std::snprintf(cold_d, sizeof cold_d, "%+.1f", e.d_cold - e.d_meas);
                if (std::isfinite(e.n_cold)) std::snprintf(cold_n, sizeof cold_n, "%+.1f", e.n_cold - e.n_meas);
                char fine_d[48] = "-", fine_n[32] = "-", cal[64] = "-";
                if (std::isfinite(e.d_fine))
                    std::snprintf(fine_d, sizeof fine_d, "%+.1f (grid %d%s)", e.d_fine - e.d_meas, e.fine_grid, e.fine_at_rest ? "" : ", not at rest");
                if (std::isfinite(e.n_fine)) std::snprintf(fine_n, sizeof fine_n, "%+.1f", e.n_fine - e.n_meas);
                if (std::isfinite(e.calibration)) std::snprintf(cal, sizeof cal, "%sx %.3f", e.calibration_profile ? "profile, bendings " : "", e.calibration);
                std::snprintf(buf, sizeof buf, "| %s | %s | %.1f | %.1f | %+.1f | %.0f | %.1f | %s | %s | %s | %s | %s | %.0f / %d | %.1f | %s | %s |\n",
                              id.c_str(), l.c_str(), e.d_meas, e.d_fit, e.d_fit - e.d_meas, e.n_meas, e.n_fit, cold_d, cold_n, fine_d, fine_n, cal,
                              e.chi2, e.dof, e.rim_z, e.exceeds ? "yes" : "no", cands.empty() ? "-" : cands.c_str());
                md << buf;
                js.push_back({{"record", id}, {"label", l}, {"model", e.model}, {"edge_contact", e.edge_contact}, {"dc_measured", e.d_meas},
                              {"dc_fitted", e.d_fit}, {"nodes_measured", e.n_meas}, {"nodes_fitted", e.n_fit},
                              {"dc_cold", std::isfinite(e.d_cold) ? nlohmann::json(e.d_cold) : nlohmann::json(nullptr)},
                              {"nodes_cold", std::isfinite(e.n_cold) ? nlohmann::json(e.n_cold) : nlohmann::json(nullptr)},
                              {"dc_cold_fine", std::isfinite(e.d_fine) ? nlohmann::json(e.d_fine) : nlohmann::json(nullptr)},
                              {"nodes_cold_fine", std::isfinite(e.n_fine) ? nlohmann::json(e.n_fine) : nlohmann::json(nullptr)},
                              {"cold_fine_grid", e.fine_grid > 0 ? nlohmann::json(e.fine_grid) : nlohmann::json(nullptr)},
                              {"cold_fine_converged", std::isfinite(e.d_fine) ? nlohmann::json(e.fine_at_rest) : nlohmann::json(nullptr)},
                              {"flat_calibration_scale", std::isfinite(e.calibration) ? nlohmann::json(e.calibration) : nlohmann::json(nullptr)},
                              {"flat_calibration_profile", e.calibration_profile},
                              {"perturbation_m", std::isfinite(e.waviness_m) ? nlohmann::json(e.waviness_m) : nlohmann::json(nullptr)},
                              {"chi2", e.chi2}, {"dof", e.dof},
                              {"rim_z", e.rim_z}, {"exceeds_noise", e.exceeds}, {"candidate_effects", e.candidates}});
            }
    return js;
}

/// The aggregates per fit (label).
void label_rows(std::ostringstream& md, const std::vector<std::string>& labels, const std::vector<Entry>& entries)
{
    char buf[512];
    md << "\n| fit | records | mean D err | RMS D err | records with \\|D err\\| <= 2 | records with \\|node err\\| <= 1 | both | both, draped from flat | "
          "both, as fitted and from flat at two grids | waviness from flat [mm] | mean chi2 / dof | beyond noise |\n"
       << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& l : labels) {
        int n = 0, dok = 0, nok = 0, both = 0, both_cold = 0, have_cold = 0, beyond = 0, all_ok = 0, have_fine = 0;
        double wmin = INFINITY, wmax = -INFINITY; // provenance.perturbation_m over the label's reports
        double s = 0, ss = 0, cd = 0;
        for (const auto& e : entries) {
            if (e.label != l) continue;
            const double d = e.d_fit - e.d_meas;
            ++n;
            s += d;
            ss += d * d;
            dok += std::abs(d) <= 2.0 ? 1 : 0;
            nok += std::abs(e.n_fit - e.n_meas) <= 1.0 ? 1 : 0;
            const bool fitted_ok = std::abs(d) <= 2.0 && std::abs(e.n_fit - e.n_meas) <= 1.0;
            both += fitted_ok ? 1 : 0;
            const bool cold_ok = std::abs(e.d_cold - e.d_meas) <= 2.0 && std::abs(e.n_cold - e.n_meas) <= 1.0;
            if (std::isfinite(e.d_cold)) {
                ++have_cold;
                both_cold += cold_ok ? 1 : 0;
            }
            // Both as fitted, and from flat on the fit's grid and the finer one.
            if (std::isfinite(e.d_cold) && std::isfinite(e.d_fine)) {
                ++have_fine;
                all_ok += (fitted_ok && cold_ok && e.fine_at_rest && std::abs(e.d_fine - e.d_meas) <= 2.0 && std::abs(e.n_fine - e.n_meas) <= 1.0) ? 1 : 0;
            }
            cd += e.chi2 / std::max(1, e.dof);
            if (std::isfinite(e.waviness_m)) wmin = std::min(wmin, e.waviness_m), wmax = std::max(wmax, e.waviness_m);
            beyond += e.exceeds ? 1 : 0;
        }
        char bc[32] = "-", ba[32] = "-", wv[48] = "- (1, not stated)";
        if (std::isfinite(wmin)) {
            if (wmax > wmin) std::snprintf(wv, sizeof wv, "%.3g-%.3g", wmin * 1e3, wmax * 1e3);
            else std::snprintf(wv, sizeof wv, "%.3g", wmin * 1e3);
        }
        if (have_cold) std::snprintf(bc, sizeof bc, "%d of %d", both_cold, have_cold);
        if (have_fine) std::snprintf(ba, sizeof ba, "%d of %d", all_ok, have_fine);
        std::snprintf(buf, sizeof buf, "| %s | %d | %+.2f | %.2f | %d | %d | %d | %s | %s | %s | %.2f | %d |\n", l.c_str(), n, s / n, std::sqrt(ss / n), dok, nok, both,
                      bc, ba, wv, cd / n, beyond);
        md << buf;
    }
}

/// dc_error.png: the D error per record (one row each), one marker per fit.
void plot_dc_error(const std::filesystem::path& out, const std::vector<std::string>& ids, const std::vector<std::string>& labels, const std::vector<Entry>& entries)
{
    estimate::Plot pl(820, 140 + 34 * static_cast<int>(ids.size()), "drape coefficient: fitted - measured", "D error [percentage points]", "");
    std::vector<std::pair<double, std::string>> ticks;
    const double dy = 0.6 / static_cast<double>(labels.size());
    for (std::size_t i = 0; i < ids.size(); ++i) {
        const double y0 = static_cast<double>(ids.size() - i);
        ticks.push_back({y0, ids[i]});
        for (std::size_t li = 0; li < labels.size(); ++li)
            for (const auto& e : entries)
                if (e.id == ids[i] && e.label == labels[li]) {
                    const double d = e.d_fit - e.d_meas, y = y0 + 0.3 - dy * (static_cast<double>(li) + 0.5);
                    pl.interval(std::min(0.0, d), d, std::max(0.0, d), y, estimate::category(static_cast<int>(li)));
                }
    }
    for (std::size_t li = 0; li < labels.size(); ++li) pl.points({}, {}, estimate::category(static_cast<int>(li)), labels[li]);
    pl.set_yticklabels(ticks);
    pl.set_yrange(0.4, static_cast<double>(ids.size()) + 0.6);
    double lo = -3, hi = 3;
    for (const auto& e : entries) lo = std::min(lo, e.d_fit - e.d_meas - 0.5), hi = std::max(hi, e.d_fit - e.d_meas + 0.5);
    pl.set_xrange(lo, hi);
    pl.line({2.0, 2.0}, {0.4, static_cast<double>(ids.size()) + 0.6}, {120, 120, 120}, "", 1, true);
    pl.line({-2.0, -2.0}, {0.4, static_cast<double>(ids.size()) + 0.6}, {120, 120, 120}, "", 1, true);
    pl.line({0.0, 0.0}, {0.4, static_cast<double>(ids.size()) + 0.6}, {0, 0, 0}, "", 1);
    std::string ls;
    for (const auto& l : labels) ls += (ls.empty() ? "" : ", ") + l;
    pl.set_caption("dashed: +-2 points. Fits: " + ls);
    pl.save((out / "dc_error.png").string());
}

/// dc_error_flat.png: the same for the presets draped from flat (the fit's grid,
/// the bar to the finer grid's drape), where reports have them: how the preset
/// drapes in a CAD.
void plot_dc_error_flat(const std::filesystem::path& out, const std::vector<std::string>& ids, const std::vector<std::string>& labels, const std::vector<Entry>& entries)
{
    if (std::none_of(entries.begin(), entries.end(), [](const Entry& e) { return std::isfinite(e.d_cold); })) return;
    estimate::Plot pl(820, 140 + 34 * static_cast<int>(ids.size()), "drape coefficient draped from flat: preset - measured",
                      "D error [percentage points]", "");
    std::vector<std::pair<double, std::string>> ticks;
    const double dy = 0.6 / static_cast<double>(labels.size());
    double lo = -3, hi = 3;
    for (std::size_t i = 0; i < ids.size(); ++i) {
        const double y0 = static_cast<double>(ids.size() - i);
        ticks.push_back({y0, ids[i]});
        for (std::size_t li = 0; li < labels.size(); ++li)
            for (const auto& e : entries)
                if (e.id == ids[i] && e.label == labels[li] && std::isfinite(e.d_cold)) {
                    const double d = e.d_cold - e.d_meas, f = std::isfinite(e.d_fine) ? e.d_fine - e.d_meas : d;
                    const double y = y0 + 0.3 - dy * (static_cast<double>(li) + 0.5);
                    pl.interval(std::min(d, f), d, std::max(d, f), y, estimate::category(static_cast<int>(li)));
                    lo = std::min(lo, std::min(d, f) - 0.5), hi = std::max(hi, std::max(d, f) + 0.5);
                }
    }
    for (std::size_t li = 0; li < labels.size(); ++li) pl.points({}, {}, estimate::category(static_cast<int>(li)), labels[li]);
    pl.set_yticklabels(ticks);
    pl.set_yrange(0.4, static_cast<double>(ids.size()) + 0.6);
    pl.set_xrange(lo, hi);
    for (const double x : {-2.0, 2.0}) pl.line({x, x}, {0.4, static_cast<double>(ids.size()) + 0.6}, {120, 120, 120}, "", 1, true);
    pl.line({0.0, 0.0}, {0.4, static_cast<double>(ids.size()) + 0.6}, {0, 0, 0}, "", 1);
    pl.set_caption("marker: the fit's grid (mean of its seeds); bar to the finer grid's drape (--flat-grid). dashed: +-2 points");
    pl.save((out / "dc_error_flat.png").string());
}

/// radius_error_LABEL.png, fold_error_LABEL.png: the contour errors against depth, per fit.
void plot_contour_errors(const std::filesystem::path& out, const std::vector<std::string>& ids, const std::vector<std::string>& labels, const std::vector<Entry>& entries)
{
    for (const auto& l : labels)
        for (const bool radius : {true, false}) {
            estimate::Plot pl(760, 460, std::string(radius ? "contour mean radius" : "RMS fold amplitude") + ": simulated - measured (" + l + ")",
                              "depth below the pedestal top [mm]", "error [mm]");
            int i = 0;
            for (const auto& id : ids)
                for (const auto& e : entries) {
                    if (e.id != id || e.label != l) continue;
                    std::vector<double> x, y;
                    for (const auto& [d, v] : radius ? e.radius : e.fold) {
                        x.push_back(d);
                        y.push_back(v);
                    }
                    if (!x.empty()) pl.line(x, y, estimate::category(i), id);
                    ++i;
                }
            pl.hline(0.0, {0, 0, 0}, false);
            pl.set_yrange(-7, 7);
            pl.save((out / ((radius ? "radius_error_" : "fold_error_") + l + ".png")).string());
        }
}

int run(const std::vector<std::string>& argv)
{
    Args a(argv, {"--out"}, {});
    const auto out = a.get("--out");
    if (!out) throw UsageError("--out DIR is required");
    if (a.positionals().empty()) throw UsageError("at least one LABEL=REPORT_DIR is required");
    std::vector<Entry> entries;
    std::vector<std::string> labels;
    for (const auto& arg : a.positionals()) {
        const auto eq = arg.find('=');
        if (eq == std::string::npos || eq == 0) throw UsageError("'" + arg + "' is not LABEL=REPORT_DIR");
        const std::string label = arg.substr(0, eq);
        for (char c : label)
            if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_')
                throw UsageError("label '" + label + "' may only hold letters, digits, '-' and '_' (it names output files)");
        if (std::find(labels.begin(), labels.end(), label) == labels.end()) labels.push_back(label);
        entries.push_back(read_report(label, arg.substr(eq + 1)));
    }
    std::filesystem::create_directories(*out);
    std::vector<std::string> ids;
    for (const auto& e : entries)
        if (std::find(ids.begin(), ids.end(), e.id) == ids.end()) ids.push_back(e.id);
    std::sort(ids.begin(), ids.end());

    std::ostringstream md;
    const nlohmann::json js = record_rows(md, ids, labels, entries);
    label_rows(md, labels, entries);
    drape::write_file_atomic((std::filesystem::path(*out) / "summary.md").string(), md.str());
    drape::write_file_atomic((std::filesystem::path(*out) / "summary.json").string(), dump_json(js) + "\n");

    plot_dc_error(*out, ids, labels, entries);
    plot_dc_error_flat(*out, ids, labels, entries);
    plot_contour_errors(*out, ids, labels, entries);
    std::cout << md.str();
    return 0;
}

} // namespace cmd_fit_summary

DRAPE_COMMAND({"fit-summary", "tables and plots across fit reports (records x models), e.g. before/after", cmd_fit_summary::kUsage, cmd_fit_summary::run});

} // namespace drape::cli
