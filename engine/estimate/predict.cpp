#include "engine/estimate/predict.hpp"

#include "engine/cloth/rest_sensitivity.hpp"
#include "engine/core/clock.hpp"
#include "engine/core/error.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace drape::estimate {

namespace {

/// The range of grids a default prediction grid is kept in (odd: the centre a node).
constexpr int kMinDefaultGrid = 9;
constexpr int kMaxDefaultGrid = 201;
constexpr int kUnfittedGrid = 31;

/// The parameters a fitted coordinate sets ("bend_Nm": both bendings).
std::vector<cloth::Param> coordinate_params(const std::string& key)
{
    if (key == "bend_Nm") return {cloth::Param::BendWarp, cloth::Param::BendWeft};
    if (const cloth::ParamSpec* sp = cloth::find_param(key)) return {sp->id};
    return {};
}

bool coordinate_is_log(const std::string& key)
{
    if (key == "bend_Nm") return true;
    const cloth::ParamSpec* sp = cloth::find_param(key);
    return sp && sp->log_scale;
}

/// Prediction::sigma_transfer_percent and what it is measured from: the fitted
/// record nearest to out.setup in log overhang (R1 - R2) and disc-to-specimen
/// ratio R2 / R1, from the preset's fit.records.
void transfer_term(const fabric::FabricPreset& preset, Prediction& out, double fraction)
{
    if (!preset.fit || !preset.fit->details.is_object() || !preset.fit->details.contains("records") ||
        !preset.fit->details["records"].is_array())
        return;
    const double R1 = out.setup.sample_diameter / 2, R2 = out.setup.disc_diameter / 2;
    double best = HUGE_VAL;
    for (const auto& rec : preset.fit->details["records"]) {
        if (!rec.is_object() || !rec.contains("sample_diameter_m") || !rec["sample_diameter_m"].is_number() ||
            !rec.contains("disc_diameter_m") || !rec["disc_diameter_m"].is_number() || !rec.contains("measured_drape_coefficient_percent") ||
            !rec["measured_drape_coefficient_percent"].is_number())
            continue;
        const double r1 = rec["sample_diameter_m"].get<double>() / 2, r2 = rec["disc_diameter_m"].get<double>() / 2;
        const double d = rec["measured_drape_coefficient_percent"].get<double>();
        if (!(r1 > r2 && r2 > 0) || !std::isfinite(d)) continue;
        const double dist = std::abs(std::log((R1 - R2) / (r1 - r2))) + std::abs(R2 / R1 - r2 / r1);
        if (dist < best) {
            best = dist;
            out.transfer_from = rec.value("id", std::string("record"));
            out.fitted_setup = std::abs(r1 - R1) < 1e-4 && std::abs(r2 - R2) < 1e-4;
            out.transfer_change_percent = out.dc_percent - d;
        }
    }
    out.sigma_transfer_percent = out.fitted_setup || out.transfer_from.empty() ? 0.0 : fraction * std::abs(out.transfer_change_percent);
}

} // namespace

std::optional<int> fit_grid_for(const fabric::FabricPreset& preset, double sample_diameter)
{
    if (!preset.provenance || preset.provenance->grid <= 0) return std::nullopt;
    const double fit_D1 = preset.fit && preset.fit->sample_diameter_m > 0 ? preset.fit->sample_diameter_m : 0.30;
    int g = static_cast<int>(std::lround(preset.provenance->grid * sample_diameter / fit_D1));
    if (g % 2 == 0) ++g;
    return std::clamp(g, kMinDefaultGrid, kMaxDefaultGrid);
}

cloth::DrapeSetup prediction_setup(const fabric::FabricPreset& preset, cloth::DrapeSetup s)
{
    s = preset.laid(s);
    if (s.grid <= 0) s.grid = fit_grid_for(preset, s.sample_diameter).value_or(kUnfittedGrid);
    if (preset.provenance) {
        const auto& d = preset.provenance->details;
        if (d.is_object() && d.contains("mesh") && d["mesh"].is_string()) s.mesh = cloth::drape_mesh_from_string(d["mesh"].get<std::string>());
    }
    return s;
}

Eigen::MatrixXd fit_covariance(const fabric::FabricPreset& preset, std::vector<std::string>& keys)
{
    keys.clear();
    if (!preset.fit) return {};
    const auto& d = preset.fit->details;
    if (!d.is_object() || !d.contains("correlation") || !d["correlation"].is_object() || !d.contains("parameters") ||
        !d["parameters"].is_array())
        return {};
    // The sigma of each fitted coordinate from the parameter table's rows.
    auto sigma_of = [&](const std::string& key) {
        const std::string row = key == "bend_Nm" ? "bend_warp_Nm" : key;
        for (const auto& p : d["parameters"])
            if (p.is_object() && p.value("key", std::string()) == row && p.value("role", std::string()) == "fitted" &&
                p.contains("sigma_search_coordinate") && p["sigma_search_coordinate"].is_number())
                return p["sigma_search_coordinate"].get<double>();
        return std::numeric_limits<double>::quiet_NaN();
    };
    const auto& corr = d["correlation"];
    std::vector<double> sig;
    for (auto it = corr.begin(); it != corr.end(); ++it) {
        const double s = sigma_of(it.key());
        if (!std::isfinite(s) || coordinate_params(it.key()).empty()) continue; // held, not seen, or unknown
        keys.push_back(it.key());
        sig.push_back(s);
    }
    const int n = static_cast<int>(keys.size());
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < n; ++k) {
            double rho = i == k ? 1.0 : 0.0;
            const auto& row = corr[keys[static_cast<std::size_t>(i)]];
            if (i != k && row.is_object() && row.contains(keys[static_cast<std::size_t>(k)]) &&
                row[keys[static_cast<std::size_t>(k)]].is_number())
                rho = std::clamp(row[keys[static_cast<std::size_t>(k)]].get<double>(), -1.0, 1.0);
            C(i, k) = rho * sig[static_cast<std::size_t>(i)] * sig[static_cast<std::size_t>(k)];
        }
    return C;
}

Prediction predict_drape(const fabric::FabricPreset& preset, const cloth::DrapeSetup& setup_in, const PredictOptions& o)
{
    if (o.seeds < 1) throw ParameterError("predict: seeds " + std::to_string(o.seeds) + " must be at least 1");
    const auto t0 = std::chrono::steady_clock::now();
    Prediction out;
    out.setup = setup_in;
    out.setup.validate();
    const cloth::Material material = preset.material();
    for (int k = 0; k < o.seeds; ++k) {
        if (o.cancel && o.cancel->load()) break;
        if (o.on_drape) o.on_drape(k, o.seeds);
        cloth::DrapeSetup s = out.setup;
        s.seed = out.setup.seed + static_cast<std::uint64_t>(k);
        out.drapes.push_back(cloth::simulate_drape(material, s, o.rest, preset.model));
        out.converged = out.converged && out.drapes.back().status.converged();
    }
    if (out.drapes.empty()) return out;
    std::vector<double> dc;
    std::vector<int> nodes;
    for (const auto& r : out.drapes) {
        dc.push_back(r.metrics.drape_coefficient_percent);
        nodes.push_back(r.metrics.node_count);
    }
    const double n = static_cast<double>(dc.size());
    out.dc_percent = std::accumulate(dc.begin(), dc.end(), 0.0) / n;
    std::vector<int> sorted = nodes;
    std::sort(sorted.begin(), sorted.end());
    out.node_count = sorted[sorted.size() / 2];
    out.node_min = sorted.front();
    out.node_max = sorted.back();
    double var_starts = 0;
    for (double v : dc) var_starts += (v - out.dc_percent) * (v - out.dc_percent);
    // The spread of the drapes over the starts; with one drape there is none to see.
    out.sigma_starts_percent = dc.size() > 1 ? std::sqrt(var_starts / (n - 1)) : 0.0;
    out.sigma_repeat_percent = o.repeat_sigma_percent;
    out.dc_lower95 = out.dc_upper95 = std::numeric_limits<double>::quiet_NaN();
    out.nodes_lower = out.node_min;
    out.nodes_upper = out.node_max;
    if (o.intervals) {
        // The fit's covariance through the exact sensitivity of D at the first
        // drape's rest state (a seed-19 preset has grid springs, not continuum
        // parameters, and no covariance).
        const Eigen::MatrixXd C = fit_covariance(preset, out.parameter_keys);
        if (C.size() > 0 && !preset.is_seed() && out.drapes.front().status.converged()) {
            std::vector<cloth::Param> ps;
            for (const auto& key : out.parameter_keys)
                for (cloth::Param p : coordinate_params(key))
                    if (preset.params[p] != 0 && std::find(ps.begin(), ps.end(), p) == ps.end()) ps.push_back(p);
            std::vector<cloth::DrapeMetricSensitivity> sens;
            try {
                sens = cloth::drape_metric_sensitivities(material, out.setup, out.drapes.front().x, ps, preset.model);
            } catch (const Error&) {
                sens.clear(); // not a stable rest state: no linearisation (the term stays 0, parameters_known false)
            }
            if (!sens.empty()) {
                Eigen::VectorXd g = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(out.parameter_keys.size()));
                for (std::size_t i = 0; i < out.parameter_keys.size(); ++i) {
                    const std::string& key = out.parameter_keys[i];
                    for (cloth::Param p : coordinate_params(key))
                        for (const auto& s : sens)
                            if (s.param == p)
                                // per decade of a log coordinate: dD/dlog10 p = p ln 10 dD/dp
                                g[static_cast<Eigen::Index>(i)] += coordinate_is_log(key) ? s.value * std::log(10.0) * s.d_drape_coefficient_percent
                                                                                          : s.d_drape_coefficient_percent;
                }
                out.d_dc_per_coordinate.assign(g.data(), g.data() + g.size());
                out.sigma_parameters_percent = std::sqrt(std::max(0.0, g.dot(C * g)));
                out.parameters_known = true;
            }
        }
        transfer_term(preset, out, o.transfer_fraction);
        const double sigma = std::sqrt(out.sigma_parameters_percent * out.sigma_parameters_percent +
                                       out.sigma_starts_percent * out.sigma_starts_percent +
                                       out.sigma_repeat_percent * out.sigma_repeat_percent +
                                       out.sigma_transfer_percent * out.sigma_transfer_percent);
        out.dc_lower95 = std::max(0.0, out.dc_percent - 1.96 * sigma);
        out.dc_upper95 = std::min(100.0, out.dc_percent + 1.96 * sigma);
        out.nodes_lower = std::max(0, out.node_min - o.repeat_folds);
        out.nodes_upper = out.node_max + o.repeat_folds;
    }
    out.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    return out;
}

} // namespace drape::estimate
