#include "engine/estimate/fit.hpp"
#include "engine/cloth/blas_threads.hpp"
#include "engine/core/clock.hpp"

#include "engine/fabric/preset.hpp"

#include <cmath>
#include <ctime>
#include <limits>

namespace drape::estimate {

using nlohmann::json;

namespace {

/// Where the preset came from: the tool, the records and how the fit simulated them.
fabric::Provenance provenance_of(const FitResult& r)
{
    fabric::Provenance provenance;
    provenance.tool = "drape fit";
    provenance.date = utc_now();
    provenance.grid = r.options.grid;
    json prov;
    json recs = json::array();
    for (const auto& rf : r.records) {
        recs.push_back({{"id", rf.measured.id}, {"source", rf.measured.source}});
        provenance.records.push_back(rf.measured.id);
    }
    prov["records"] = recs;
    prov["recentre_contours"] = r.options.recentre_contours;
    prov["untilt_contours"] = r.options.untilt_contours;
    prov["edge_contact"] = r.options.model_options.edge_contact;
    prov["bending_correction"] = r.options.model_options.bending_correction;
    prov["arc_membrane"] = r.options.model_options.arc_membrane;
    prov["mesh"] = cloth::to_string(r.options.mesh);
    prov["model"] = to_string(r.options.model);
    prov["seed"] = r.options.seed;
    if (!r.blas_kernel.empty()) prov["blas_kernel"] = r.blas_kernel; // the rounding of its drapes (cloth::portable_blas_kernel)
    prov["seeds_per_evaluation"] = r.options.seeds_per_evaluation;
    prov["global_stage_starts"] = r.options.warm_global ? "warm" : "cold";
    prov["local_stage_starts"] = r.options.warm_local ? "warm" : "cold";
    prov["channels"] = r.options.channels;
    prov["fold_branch"] = to_string(r.options.branch);
    if (r.options.branch != FoldBranch::Random) prov["fold_branch_lift_m"] = r.options.branch_lift_m;
    provenance.details = prov;
    // How the records' lab laid them (the from-flat drapes' first rest): the
    // preset is laid so by drape simulate / predict (FabricPreset::laying).
    provenance.laying_load = r.options.laying_load;
    provenance.perturbation_m = r.options.perturbation_m;
    return provenance;
}

/// The search: its counts, trace, time and grid refinement.
void add_search(json& fit, const FitResult& r)
{
    fit["evaluations"] = r.evaluations;
    fit["simulations"] = r.simulations;
    fit["method"] = to_string(r.options.method);
    fit["factorisations"] = r.factorisations;
    fit["back_substitutions"] = r.back_substitutions;
    fit["jacobian_jumps"] = r.jacobian_jumps;
    fit["jacobians"] = r.jacobians;
    json trace = json::array();
    for (const auto& t : r.trace)
        trace.push_back({{"evaluation", t.evaluation}, {"stage", t.stage}, {"chi2", t.chi2}, {"best_chi2", t.best_chi2},
                         {"coords", t.coords}, {"elapsed_s", t.elapsed_s}});
    fit["trace"] = trace;
    fit["seconds_per_simulation"] = r.seconds_per_simulation();
    fit["wall_seconds"] = r.wall_seconds;
    fit["cancelled"] = r.cancelled;
    if (r.refinement.from_grid > 0)
        fit["refinement"] = {{"from_grid", r.refinement.from_grid}, {"to_grid", r.refinement.to_grid},
                             {"adopted", r.refinement.adopted},   {"coarse_chi2", r.refinement.coarse_chi2},
                             {"coarse_dof", r.refinement.coarse_dof}, {"fine_chi2", r.refinement.fine_chi2},
                             {"fine_dof", r.refinement.fine_dof}, {"reason", r.refinement.reason}};
}

/// The priors and what they decided.
void add_priors(json& fit, const FitResult& r)
{
    fit["bending"] = to_string(r.options.bending);
    fit["priors_on"] = r.options.priors;
    if (!r.priors.empty()) {
        json pr = json::array();
        for (const auto& u : r.priors)
            pr.push_back({{"kind", u.kind},
                          {"value_decades", u.value},
                          {"centre_decades", u.centre},
                          {"prior_sigma_decades", u.prior_sigma},
                          {"data_sigma_decades", std::isfinite(u.data_sigma) ? json(u.data_sigma) : json(nullptr)},
                          {"decided_by_prior", u.decided_by_prior}});
        fit["priors"] = pr;
    }
}

/// The flat calibration: the steps it tried and what it moved.
void add_flat_calibration(json& fit, const FitResult& r)
{
    if (!r.flat_calibration.tried) return;
    const auto& c = r.flat_calibration;
    fit["flat_calibration"] = {{"applied", c.applied},
                               {"scale", c.scale},
                               {"error_before_percent", c.error_before},
                               {"error_after_percent", c.error_after},
                               {"tolerance_percent", c.tolerance},
                               {"bend_warp_fitted_Nm", c.bend_warp_fitted},
                               {"bend_weft_fitted_Nm", c.bend_weft_fitted},
                               {"chi2_increase_linearised", std::isfinite(c.chi2_increase) ? json(c.chi2_increase) : json(nullptr)},
                               {"chi2_preset", c.applied && std::isfinite(c.chi2_preset) ? json(c.chi2_preset) : json(nullptr)},
                               {"steps", c.steps},
                               {"fold_error_before", c.fold_error_before},
                               {"fold_error_after", c.fold_error_after},
                               {"fold_search", c.fold_search},
                               {"fold_sigmas", c.fold_sigmas},
                               {"reason", c.reason}};
    json tried = json::array();
    for (const auto& t : c.history)
        tried.push_back({{"kind", t.kind},
                         {"scale", t.scale},
                         {"sigmas", t.sigmas},
                         {"error_percent", t.error},
                         {"fold_error", t.fold_error},
                         {"finer_grid", t.finer_grid},
                         {"chi2_increase_linearised", std::isfinite(t.chi2_cost) ? json(t.chi2_cost) : json(nullptr)}});
    fit["flat_calibration"]["steps_tried"] = tried;
    json moved = json::object();
    for (const auto& m : c.moved) moved[m.key] = {{"before", m.before}, {"after", m.after}};
    fit["flat_calibration"]["moved"] = moved;
}

/// The warp/weft ratio and the tie; the shear and its hold.
void add_anisotropy_and_shear(json& fit, const FitResult& r)
{
    if (r.anisotropy.assessed) {
        const auto& a = r.anisotropy;
        json an = {{"ratio_warp_weft", a.ratio},
                   {"ratio_lower95", a.ratio_lower95},
                   {"ratio_upper95", std::isfinite(a.ratio_upper95) ? json(a.ratio_upper95) : json(nullptr)},
                   {"separated", a.separated},
                   {"setups", a.setups},
                   {"setups_confirming", a.setups_confirming},
                   {"tied_refit", a.refit},
                   {"tied", a.tied},
                   {"reason", a.reason}};
        if (a.refit) {
            an["free_chi2"] = a.free_chi2;
            an["free_dof"] = a.free_dof;
            an["tied_chi2"] = a.tied_chi2;
            an["tied_dof"] = a.tied_dof;
            an["delta_chi2_scaled"] = a.delta_chi2;
        }
        fit["bending_anisotropy"] = an;
    }
    if (r.shear_hold.assessed) {
        const auto& h = r.shear_hold;
        json sh = {{"mode", to_string(r.options.shear)},
                   {"fitted_N_m", h.fitted_N_m},
                   {"fitted_lower95_N_m", h.lower95_N_m},
                   {"fitted_upper95_N_m", h.upper95_N_m},
                   {"at_bound", h.at_bound},
                   {"constrained", h.constrained},
                   {"held_refit", h.tried},
                   {"held", h.held},
                   {"reason", h.reason}};
        if (h.tried) {
            sh["held_N_m"] = h.held_N_m;
            sh["fitted_chi2"] = h.fitted_chi2;
            sh["held_chi2"] = h.held_chi2;
            sh["delta_chi2_scaled"] = h.delta_chi2;
        }
        fit["shear_hold"] = sh;
    }
}

/// The parameter table and the correlations of the fitted coordinates.
void add_parameters(json& fit, const FitResult& r)
{
    json params = json::array();
    std::vector<std::string> not_identifiable;
    for (const auto& e : r.estimates) {
        json p = {{"key", e.key}, {"unit", e.unit}, {"role", e.role}, {"value", e.value}, {"constrained", e.constrained}};
        if (e.role == "fitted") {
            p["lower95"] = e.lower95;
            p["upper95"] = e.upper95;
            p["sigma_search_coordinate"] = std::isfinite(e.sigma_coord) ? json(e.sigma_coord) : json(nullptr);
        }
        if (!e.note.empty()) p["note"] = e.note;
        if (!e.constrained) not_identifiable.push_back(e.key);
        params.push_back(p);
    }
    fit["parameters"] = params;
    fit["not_constrained"] = not_identifiable;
    json corr = json::object();
    const int n = static_cast<int>(r.variables.size());
    for (int i = 0; i < n; ++i) {
        json row = json::object();
        for (int k = 0; k < n; ++k) {
            const double c = r.correlation.size() ? r.correlation(i, k) : std::numeric_limits<double>::quiet_NaN();
            row[r.variables[k].name] = std::isfinite(c) ? json(c) : json(nullptr);
        }
        corr[r.variables[i].name] = row;
    }
    fit["correlation"] = corr;
}

/// Per record: D and nodes measured, fitted, as saved and from flat.
json records_json(const FitResult& r)
{
    json per = json::array();
    for (const auto& rf : r.records) {
        per.push_back({{"id", rf.measured.id},
                       {"sample_diameter_m", rf.measured.sample_diameter},
                       {"disc_diameter_m", rf.measured.disc_diameter},
                       {"pedestal_side_photo_diameter_m", std::isfinite(rf.measured.pedestal_measured_diameter)
                                                              ? json(rf.measured.pedestal_measured_diameter) : json(nullptr)},
                       {"measured_drape_coefficient_percent", rf.measured_features.drape_coefficient_percent},
                       {"fitted_drape_coefficient_percent", rf.simulated_features.drape_coefficient_percent},
                       {"dc_error_percent", rf.dc_error_percent},
                       {"measured_node_count", rf.measured_features.node_count},
                       {"fitted_node_count", rf.simulated_features.node_count},
                       {"node_error", rf.node_error},
                       {"fold_branch", rf.branch_folds > 0 ? json(rf.branch_folds) : json(nullptr)},
                       {"preset_moved", rf.preset_moved},
                       {"preset_converged", rf.preset_converged},
                       {"preset_drape_coefficient_percent", rf.preset_features.drape_coefficient_percent},
                       {"preset_node_count", rf.preset_features.node_count},
                       {"preset_dc_error_percent", rf.preset_dc_error_percent},
                       {"preset_node_error", rf.preset_node_error},
                       {"cold_seeds", rf.cold_seeds},
                       {"cold_drape_coefficient_percent", rf.cold_seeds ? json(rf.cold_features.drape_coefficient_percent) : json(nullptr)},
                       {"cold_node_count", rf.cold_seeds ? json(rf.cold_features.node_count) : json(nullptr)},
                       {"cold_dc_error_percent", rf.cold_seeds ? json(rf.cold_dc_error_percent) : json(nullptr)},
                       {"cold_node_error", rf.cold_seeds ? json(rf.cold_node_error) : json(nullptr)},
                       {"cold_fine_grid", rf.cold_fine_grid ? json(rf.cold_fine_grid) : json(nullptr)},
                       {"cold_fine_converged", rf.cold_fine_grid ? json(rf.cold_fine_converged) : json(nullptr)},
                       {"cold_fine_drape_coefficient_percent", rf.cold_fine_grid ? json(rf.cold_fine_features.drape_coefficient_percent) : json(nullptr)},
                       {"cold_fine_node_count", rf.cold_fine_grid ? json(rf.cold_fine_features.node_count) : json(nullptr)},
                       {"cold_fine_dc_error_percent", rf.cold_fine_grid ? json(rf.cold_fine_dc_error_percent) : json(nullptr)},
                       {"cold_fine_node_error", rf.cold_fine_grid ? json(rf.cold_fine_node_error) : json(nullptr)},
                       {"free_strip_bending_bound_Nm", std::isfinite(rf.free_strip_bound_Nm) ? json(rf.free_strip_bound_Nm) : json(nullptr)},
                       {"free_strip_preset_drape_coefficient_percent",
                        std::isfinite(rf.free_strip_preset_dc_percent) ? json(rf.free_strip_preset_dc_percent) : json(nullptr)},
                       {"below_free_strips", rf.below_free_strips},
                       {"node_source", rf.measured.node_source},
                       {"contours_recentred", rf.measured.recentre_contours},
                       {"contours_untilted", rf.measured.untilt_contours},
                       {"profiler_axis_offset_m", {rf.measured_features.axis_offset_m.x(), rf.measured_features.axis_offset_m.y()}},
                       {"profiler_axis_tilt_rad", {rf.measured_features.axis_tilt.x(), rf.measured_features.axis_tilt.y()}}});
    }
    return per;
}

/// The preset's own drape coefficient on its first record's set-up: draped from
/// flat (as predict, a CAD and the library use it) when the fit ran those drapes,
/// else as fitted.
void set_drape_reference(fabric::FabricPreset& preset, fabric::FitSummary& summary, const FitResult& r, const std::string& date)
{
    if (r.records.empty()) return;
    summary.sample_diameter_m = r.records.front().measured.sample_diameter;
    summary.disc_diameter_m = r.records.front().measured.disc_diameter;
    const RecordFit& rf = r.records.front();
    fabric::DrapeReference d;
    const bool cold = rf.cold_seeds > 0 && std::isfinite(rf.cold_features.drape_coefficient_percent);
    d.percent = cold ? rf.cold_features.drape_coefficient_percent : rf.simulated_features.drape_coefficient_percent;
    d.kind = "simulated";
    d.sample_diameter_m = rf.measured.sample_diameter;
    d.disc_diameter_m = rf.measured.disc_diameter;
    d.method = cold ? "drape fit: mean of " + std::to_string(rf.cold_seeds) + " drapes from flat (random start) at grid " +
                          std::to_string(r.options.grid)
                    : "drape fit: fitted drapes at grid " + std::to_string(r.options.grid);
    d.date = date;
    if (std::isfinite(d.percent)) preset.drape = d;
}

} // namespace

json fit_to_json(const FitResult& r)
{
    fabric::FabricPreset preset;
    preset.name = r.name.empty() ? (r.records.empty() ? std::string("fitted") : r.records.front().measured.id) : r.name;
    preset.params = r.params;
    preset.model = r.options.model_options; // what the fit simulated with (edge contact)
    preset.source = "fitted by drape fit to drape-test records";
    preset.provenance = provenance_of(r);

    fabric::FitSummary summary;
    summary.chi2 = r.chi2;
    summary.dof = r.dof;
    summary.reduced_chi2 = r.chi2 / std::max(1, r.dof);
    summary.grid_bound = r.grid_bound;
    json fit;
    add_search(fit, r);
    add_priors(fit, r);
    add_flat_calibration(fit, r);
    add_anisotropy_and_shear(fit, r);
    add_parameters(fit, r);
    fit["records"] = records_json(r);
    summary.details = fit;
    set_drape_reference(preset, summary, r, preset.provenance->date);
    preset.fit = summary;
    preset.extra["residual"] = residual_to_json(r.residual);
    return fabric::fabric_to_json(preset);
}

} // namespace drape::estimate
