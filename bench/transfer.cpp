#include "bench/transfer.hpp"

#include "engine/core/error.hpp"
#include "engine/estimate/plot.hpp"
#include "engine/fabric/preset.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>

namespace drape::bench {

namespace fs = std::filesystem;

namespace {

std::string fmt(const char* f, double v)
{
    char b[64];
    std::snprintf(b, sizeof b, f, v);
    return b;
}

std::string setup_label(const estimate::MeasuredDrape& m)
{
    return fmt("%.0f", m.sample_diameter * 1e3) + "/" + fmt("%.0f", m.disc_diameter * 1e3);
}

/// The subsets of `n` set-ups a mode fits.
std::vector<std::vector<int>> subsets(const std::string& mode, int n)
{
    std::vector<std::vector<int>> out;
    if (mode == "single")
        for (int i = 0; i < n; ++i) out.push_back({i});
    else if (mode == "pair")
        for (int i = 0; i < n; ++i)
            for (int k = i + 1; k < n; ++k) out.push_back({i, k});
    else if (mode == "all") {
        if (n >= 2) {
            std::vector<int> all(static_cast<std::size_t>(n));
            for (int i = 0; i < n; ++i) all[static_cast<std::size_t>(i)] = i;
            out.push_back(all);
        }
    } else
        throw ParameterError("transfer: mode '" + mode + "' is not one of single, pair, all");
    return out;
}

/// What the report says the data did not decide: parameters at a fit bound,
/// held or tied, decided by a prior.
std::string fit_notes(const estimate::FitResult& r)
{
    std::vector<std::string> n;
    for (const auto& e : r.estimates) {
        if (e.role == "held") n.push_back(e.key + " held");
        if (e.role == "fitted" && e.note.find("at the fit bound") != std::string::npos) n.push_back(e.key + " at bound");
        if (e.role == "fitted" && e.note.find("prior") != std::string::npos) n.push_back(e.key + " prior");
    }
    if (r.anisotropy.tied) n.push_back("bendings tied");
    std::string s;
    for (const auto& x : n) s += (s.empty() ? "" : "; ") + x;
    return s;
}

} // namespace

std::vector<TransferRecord> load_transfer_records(const std::string& dir)
{
    std::vector<std::string> dirs;
    std::error_code ec;
    for (const auto& e : fs::directory_iterator(dir, ec))
        if (e.is_directory() && fs::exists(e.path() / "meta.json")) dirs.push_back(e.path().string());
    if (ec) throw FileError(dir + ": " + ec.message());
    std::sort(dirs.begin(), dirs.end());
    std::vector<TransferRecord> out;
    const std::regex tail(R"(^(.*)-(\d+)-(\d+)$)");
    for (const auto& d : dirs) {
        TransferRecord t;
        t.record = estimate::load_record(d);
        std::smatch m;
        t.fabric = std::regex_match(t.record.id, m, tail) ? m[1].str() : t.record.id;
        t.setup = setup_label(t.record);
        out.push_back(std::move(t));
    }
    return out;
}

std::vector<TransferRow> run_transfer(const std::vector<TransferRecord>& records, const TransferOptions& o)
{
    std::map<std::string, std::vector<const TransferRecord*>> by_fabric;
    for (const auto& r : records)
        if (o.fabrics.empty() || o.fabrics.count(r.fabric)) by_fabric[r.fabric].push_back(&r);
    std::vector<TransferRow> rows;
    for (const auto& [fabric, recs] : by_fabric) {
        const int n = static_cast<int>(recs.size());
        if (n < 2 && o.fabrics.empty()) continue; // nothing to predict
        for (const auto& mode : o.modes)
            for (const auto& sub : subsets(mode, n)) {
                std::vector<estimate::MeasuredDrape> fit_recs;
                std::string fitted;
                for (int i : sub) {
                    fit_recs.push_back(recs[static_cast<std::size_t>(i)]->record);
                    fitted += (fitted.empty() ? "" : "+") + recs[static_cast<std::size_t>(i)]->setup;
                }
                std::string file = fabric + "_" + fitted + ".json";
                std::replace(file.begin(), file.end(), '/', '-');
                estimate::FitResult fr;
                fabric::FabricPreset preset;
                if (!o.replay_presets.empty()) {
                    preset = fabric::load_fabric(o.replay_presets + "/" + file);
                    fr.params = preset.params;
                    fr.chi2 = preset.fit ? preset.fit->chi2 : 0;
                    fr.dof = preset.fit ? preset.fit->dof : 0;
                    if (preset.fit && preset.fit->details.contains("wall_seconds")) fr.wall_seconds = preset.fit->details["wall_seconds"].get<double>();
                } else {
                    if (o.log) o.log(fabric + " " + mode + " fit of " + fitted + " ...");
                    fr = estimate::fit_fabric(fit_recs, o.fit);
                    fr.name = fabric;
                    const auto j = estimate::fit_to_json(fr);
                    preset = fabric::fabric_from_json(j, fabric + " (" + fitted + ")");
                    if (!o.save_presets.empty()) {
                        fs::create_directories(o.save_presets);
                        std::ofstream(o.save_presets + "/" + file) << j.dump(1) << "\n";
                    }
                }
                if (o.laying_load > 0 || o.perturbation_m >= 0) {
                    if (!preset.provenance) preset.provenance = fabric::Provenance{};
                    if (o.laying_load > 0) preset.provenance->laying_load = o.laying_load;
                    if (o.perturbation_m >= 0) preset.provenance->perturbation_m = o.perturbation_m;
                }
                if (o.log)
                    o.log(fabric + " " + mode + " fit of " + fitted + ": " + fmt("%.1f s", fr.wall_seconds) + ", chi2 " + fmt("%.1f", fr.chi2) +
                          " / " + std::to_string(fr.dof) + ", bendings " + fmt("%.3g", fr.params[cloth::Param::BendWarp]) + " / " +
                          fmt("%.3g", fr.params[cloth::Param::BendWeft]) + " N*m");
                for (int t = 0; t < n; ++t) {
                    const bool held = std::find(sub.begin(), sub.end(), t) == sub.end();
                    if (!held && !o.in_sample && mode != "all") continue;
                    const auto& target = recs[static_cast<std::size_t>(t)]->record;
                    TransferRow row;
                    row.fabric = fabric;
                    row.mode = mode;
                    row.fitted = fitted;
                    row.target = recs[static_cast<std::size_t>(t)]->setup;
                    row.held_out = held;
                    row.d_lab = target.drape_coefficient_percent;
                    row.n_lab = target.node_count;
                    row.fit_seconds = fr.wall_seconds;
                    row.chi2 = fr.chi2;
                    row.dof = fr.dof;
                    row.warp_weft_ratio = fr.params[cloth::Param::BendWarp] / fr.params[cloth::Param::BendWeft];
                    row.fit_notes = o.replay_presets.empty() ? fit_notes(fr) : std::string("replayed");
                    cloth::DrapeSetup s;
                    s.sample_diameter = target.sample_diameter;
                    s.disc_diameter = target.disc_diameter;
                    s.pedestal_height = target.pedestal_height;
                    s.grid = 0; // the fit's grid scaled, as drape predict
                    row.prediction = estimate::predict_drape(preset, estimate::prediction_setup(preset, s), o.predict);
                    if (o.log)
                        o.log("  " + row.target + (held ? " (held out)" : " (fitted)") + ": D " + fmt("%.1f", row.prediction.dc_percent) +
                              " % [" + fmt("%.1f", row.prediction.dc_lower95) + ", " + fmt("%.1f", row.prediction.dc_upper95) +
                              "] against " + fmt("%.1f", row.d_lab) + " %, folds " + std::to_string(row.prediction.node_count) +
                              " against " + std::to_string(row.n_lab));
                    rows.push_back(std::move(row));
                }
            }
    }
    return rows;
}

TransferSummary summarise(const std::vector<TransferRow>& rows)
{
    TransferSummary s;
    double single_sum = 0, pair_sum = 0;
    std::set<std::string> fits_beyond3;
    for (const auto& r : rows) {
        const double e = std::abs(r.d_error());
        const int ne = std::abs(r.n_error());
        const std::string fit_id = r.fabric + "|" + r.mode + "|" + r.fitted;
        const double ratio = std::max(r.warp_weft_ratio, 1 / r.warp_weft_ratio);
        if (ratio > 3) fits_beyond3.insert(fit_id);
        if (r.mode == "single") s.fit_seconds_max_single = std::max(s.fit_seconds_max_single, r.fit_seconds);
        if (r.mode == "pair") s.fit_seconds_max_pair = std::max(s.fit_seconds_max_pair, r.fit_seconds);
        if (r.mode == "all") s.fit_seconds_max_all = std::max(s.fit_seconds_max_all, r.fit_seconds);
        if (r.mode == "all") {
            ++s.all_n;
            if (e <= 2 && ne <= 1) ++s.all_ok;
        }
        if (!r.held_out) continue;
        ++s.interval_n;
        if (r.inside()) ++s.interval_in;
        if (r.mode == "single") {
            ++s.single_n;
            if (e <= 3 && ne <= 1) ++s.single_ok;
            if (e > 6) ++s.single_beyond6;
            s.single_max_abs = std::max(s.single_max_abs, e);
            single_sum += e;
        } else if (r.mode == "pair") {
            ++s.pair_n;
            if (e <= 2 && ne <= 1) ++s.pair_ok;
            s.pair_max_abs = std::max(s.pair_max_abs, e);
            pair_sum += e;
        }
    }
    s.single_mean_abs = s.single_n ? single_sum / s.single_n : 0;
    s.pair_mean_abs = s.pair_n ? pair_sum / s.pair_n : 0;
    s.ratio_beyond3 = static_cast<int>(fits_beyond3.size());
    return s;
}

void write_transfer_csv(const std::vector<TransferRow>& rows, const std::string& path)
{
    std::ofstream f(path);
    if (!f) throw FileError(path + ": cannot be written");
    f << "fabric,mode,fitted,target,held_out,d_lab,d_pred,d_error,d_lower95,d_upper95,inside,n_lab,n_pred,n_error,n_lower,n_upper,"
         "sigma_parameters,sigma_starts,sigma_repeat,sigma_transfer,transfer_change,fit_seconds,predict_seconds,chi2,dof,warp_weft_ratio,converged,fit_notes\n";
    for (const auto& r : rows) {
        const auto& p = r.prediction;
        f << r.fabric << ',' << r.mode << ',' << r.fitted << ',' << r.target << ',' << (r.held_out ? 1 : 0) << ',' << fmt("%.2f", r.d_lab)
          << ',' << fmt("%.2f", p.dc_percent) << ',' << fmt("%+.2f", r.d_error()) << ',' << fmt("%.2f", p.dc_lower95) << ','
          << fmt("%.2f", p.dc_upper95) << ',' << (r.inside() ? 1 : 0) << ',' << r.n_lab << ',' << p.node_count << ',' << r.n_error()
          << ',' << p.nodes_lower << ',' << p.nodes_upper << ',' << fmt("%.2f", p.sigma_parameters_percent) << ','
          << fmt("%.2f", p.sigma_starts_percent) << ',' << fmt("%.2f", p.sigma_repeat_percent) << ',' << fmt("%.2f", p.sigma_transfer_percent) << ','
          << fmt("%+.2f", p.transfer_change_percent) << ',' << fmt("%.1f", r.fit_seconds) << ','
          << fmt("%.1f", p.wall_seconds) << ',' << fmt("%.2f", r.chi2) << ',' << r.dof << ',' << fmt("%.3g", r.warp_weft_ratio) << ','
          << (p.converged ? 1 : 0) << ",\"" << r.fit_notes << "\"\n";
    }
}

std::string transfer_markdown(const std::vector<TransferRow>& rows, const TransferSummary& s, const std::string& heading)
{
    std::ostringstream md;
    md << heading << "\n\n";
    md << "| fabric | fitted | predicted | D lab [%] | D predicted [%] | dD | 95 % interval | folds lab | folds predicted | dfolds | fit [s] | warp/weft | notes |\n";
    md << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const auto& r : rows) {
        const auto& p = r.prediction;
        md << "| " << r.fabric << " | " << r.fitted << " | " << r.target << (r.held_out ? "" : " (fitted)") << " | " << fmt("%.1f", r.d_lab)
           << " | " << fmt("%.1f", p.dc_percent) << " | " << fmt("%+.1f", r.d_error()) << (r.held_out && !r.inside() ? " *" : "") << " | "
           << fmt("%.1f", p.dc_lower95) << ".." << fmt("%.1f", p.dc_upper95) << " | " << (r.n_lab >= 0 ? std::to_string(r.n_lab) : "-")
           << " | " << p.node_count << " (" << p.node_min << ".." << p.node_max << ") | " << fmt("%+.0f", static_cast<double>(r.n_error()))
           << " | " << fmt("%.0f", r.fit_seconds) << " | " << fmt("%.2f", r.warp_weft_ratio) << " | " << r.fit_notes << " |\n";
    }
    md << "\n(* the record's D outside the prediction's 95 % interval.)\n\n";
    md << "| measure | value | issue's target |\n|---|---|---|\n";
    // Only the kinds of fit the run made (a --modes single run has no pair rows).
    const auto secs = [](double t) { return t > 0 ? fmt("%.0f", t) : std::string("-"); };
    if (s.single_n > 0) {
        md << "| single-set-up fits: held-out predictions within 3 points and 1 fold | " << s.single_ok << " of " << s.single_n << " | >= 15 of 18 |\n";
        md << "| single-set-up fits: held-out predictions beyond 6 points | " << s.single_beyond6 << " | 0 |\n";
        md << "| single-set-up fits: mean / largest held-out abs(dD) | " << fmt("%.2f", s.single_mean_abs) << " / "
           << fmt("%.1f", s.single_max_abs) << " | <= 2.5 / <= 6 |\n";
    }
    if (s.pair_n > 0) {
        md << "| pair fits: the third set-up within 2 points and 1 fold | " << s.pair_ok << " of " << s.pair_n << " | all |\n";
        md << "| pair fits: mean / largest abs(dD) | " << fmt("%.2f", s.pair_mean_abs) << " / " << fmt("%.1f", s.pair_max_abs) << " | |\n";
    }
    if (s.all_n > 0)
        md << "| joint fits of every set-up: in sample within 2 points and 1 fold | " << s.all_ok << " of " << s.all_n << " | (the ceiling) |\n";
    md << "| held-out predictions whose 95 % interval holds the record's D | " << s.interval_in << " of " << s.interval_n << " | >= 90 % |\n";
    md << "| fits with warp/weft bending beyond 3 | " << s.ratio_beyond3 << " | only where two set-ups confirm it |\n";
    md << "| longest fit: single / pair / all [s] | " << secs(s.fit_seconds_max_single) << " / " << secs(s.fit_seconds_max_pair) << " / "
       << secs(s.fit_seconds_max_all) << " | <= 60 / - / <= 120 |\n";
    return md.str();
}

void write_transfer_plot(const std::vector<TransferRow>& rows, const std::string& path)
{
    estimate::Plot p(900, 700, "Predicted against measured drape coefficient: held-out set-ups, joint fits in sample", "D measured [%]", "D predicted [%]");
    p.set_xrange(0, 100);
    p.set_yrange(0, 100);
    p.line({0, 100}, {0, 100}, {150, 150, 150}, "", 1, true);
    const std::vector<std::string> modes = {"single", "pair", "all"};
    for (std::size_t m = 0; m < modes.size(); ++m) {
        std::vector<double> x, y;
        const estimate::Rgb c = estimate::category(static_cast<int>(m));
        for (const auto& r : rows) {
            if (r.mode != modes[m] || (!r.held_out && r.mode != "all")) continue;
            // the three kinds of fit side by side at each record's D, so their bars do not overlap
            const double xs = r.d_lab + 0.7 * (static_cast<double>(m) - 1.0);
            x.push_back(xs);
            y.push_back(r.prediction.dc_percent);
            if (std::isfinite(r.prediction.dc_lower95)) p.line({xs, xs}, {r.prediction.dc_lower95, r.prediction.dc_upper95}, c, "", 1);
        }
        if (!x.empty())
            p.points(x, y, c, modes[m] == "single" ? "one set-up fitted" : modes[m] == "pair" ? "two set-ups fitted" : "all fitted (in sample)", 4);
    }
    p.save(path);
}

} // namespace drape::bench
