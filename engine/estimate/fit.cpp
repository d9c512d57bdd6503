// The fit's orchestrator (docs/estimate.md "Stages in order"): one run at a grid
// (fit_at_grid: its checks, the search stages of stages.cpp and the shear hold,
// then the optimum's estimates, its later work deferred), the free fit, its
// refinement and tied refit (fit_runs), and the fit's one "done". The stages are
// in the files detail/pipeline.hpp names at each.
#include "engine/estimate/fit.hpp"

#include "engine/cloth/blas_threads.hpp"
#include "engine/cloth/elastica.hpp"
#include "engine/core/error.hpp"
#include "engine/estimate/detail/pipeline.hpp"
#include "engine/estimate/detail/stages.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <memory>

namespace drape::estimate {

using cloth::Param;
using namespace detail;

cloth::FabricParams default_fit_start()
{
    cloth::FabricParams p;
    p[Param::BucklingLength] = kTypicalBucklingLength;
    return p;
}

FitOptions drape_fit_defaults()
{
    FitOptions o;
    o.grid = 41;
    o.model_options.bending_correction = true;
    o.laying_load = cloth::kLabLaying;
    o.perturbation_m = cloth::kLabWaviness;
    o.flat_check_grid = 61;
    o.flat_calibration = true;
    o.priors = true;
    o.start = default_fit_start();
    return o;
}

std::string fit_progress_line(const FitProgress& p)
{
    char buf[320];
    if (p.stage_id == Stage::Done) {
        std::snprintf(buf, sizeof buf, "done: %d evaluations, chi2 %.1f, %ld simulations", p.evaluation, p.best_chi2, p.simulations);
        return buf;
    }
    if (p.search) {
        std::snprintf(buf, sizeof buf, "%-11s evaluation %d (at most %d), best chi2 %.1f, %ld simulations", p.stage.c_str(), p.evaluation,
                      p.planned, p.best_chi2, p.simulations);
        return buf;
    }
    // The stages after the search: what they draw.
    const char* text = "after the search";
    switch (p.stage_id) {
    case Stage::FromFlatFoldCount: text = "a calibration step along the contours' profile, from flat"; break;
    case Stage::FromFlatCalibrated: text = "the calibrated preset from flat"; break;
    case Stage::FromFlat: text = "the preset from flat on the fit's grid and the finer one"; break;
    case Stage::Effects: text = "the candidate effects"; break;
    case Stage::PresetAsSaved: text = "the preset as saved, on the fit's branch"; break;
    default: break;
    }
    std::snprintf(buf, sizeof buf, "%s%s: %ld simulations, best chi2 %.1f; %s", p.stage.c_str(), p.starting ? "" : " (done)", p.simulations,
                  p.best_chi2, text);
    return buf;
}

namespace detail {

FitResult fit_at_grid(const std::vector<MeasuredDrape>& records_in, const FitOptions& options_in, DeferredEffects& deferred,
                      const std::vector<std::vector<cloth::Positions>>* warm)
{
    deferred = nullptr;
    auto state = std::make_shared<GridRunState>();
    state->records = records_in;
    state->options = options_in;
    std::vector<MeasuredDrape>& records = state->records;
    const FitOptions& options = state->options;
    for (auto& r : records) {
        r.recentre_contours = r.recentre_contours || options.recentre_contours;
        r.untilt_contours = r.untilt_contours || options.untilt_contours;
    }
    if (records.empty()) throw ParameterError("fit: no records to fit");
    if (options.channels.empty()) throw ParameterError("fit: no channels to fit");
    for (const auto& r : records)
        if (r.untilt_contours && r.recentre_contours)
            throw ParameterError("fit: record '" + r.id + "': re-centred and untilted contours are two models of the profiler's axis - choose one");
    if (options.grid < 9 || options.grid > 200) throw ParameterError("fit: grid = " + std::to_string(options.grid) + " is outside [9, 200]");
    if (!(options.branch_lift_m > 0) || options.branch_lift_m > 0.05)
        throw ParameterError("fit: branch lift = " + std::to_string(options.branch_lift_m) + " m is outside (0, 0.05]");
    if (!(options.laying_load > 0) || options.laying_load > 1)
        throw ParameterError("fit: laying load = " + std::to_string(options.laying_load) + " is outside (0, 1] (a fraction of gravity)");
    if (!(options.perturbation_m >= 0) || options.perturbation_m > 0.05)
        throw ParameterError("fit: perturbation = " + std::to_string(options.perturbation_m) + " m is outside [0, 0.05] (the flat start's largest lift)");
    if (options.random_start_seeds < 0 || options.random_start_seeds > 16)
        throw ParameterError("fit: random_start_seeds = " + std::to_string(options.random_start_seeds) + " is outside [0, 16]");
    if (options.seeds_per_evaluation < 1 || options.seeds_per_evaluation > 16)
        throw ParameterError("fit: seeds_per_evaluation = " + std::to_string(options.seeds_per_evaluation) + " is outside [1, 16]");
    for (const auto& r : records)
        if (r.contours.empty() && !std::isfinite(r.drape_coefficient_percent))
            throw ParameterError("fit: record '" + r.id + "' has neither contours nor a drape coefficient");
    cloth::single_threaded_blas();
    const auto t0 = Clock::now();
    FitResult out;
    out.blas_kernel = cloth::blas_kernel();
    out.options = options;
    out.options.progress = nullptr;
    out.options.cancel = nullptr;
    out.variables = fit_variables(options.model, options.bending == BendingTie::Tied);
    if (options.shear_held_N_m > 0) // held from the start (the tied refit of a held fit): not a coordinate
        if (const int is = sole_variable(out.variables, Param::Shear); is >= 0) out.variables.erase(out.variables.begin() + is);
    const auto& vars = out.variables;
    const int n = static_cast<int>(vars.size());
    cloth::FabricParams base = options.start.value_or(cloth::FabricParams{});
    if (options.shear_held_N_m > 0) base[Param::Shear] = options.shear_held_N_m;
    if (options.model == ModelVariant::Baseline) base[Param::Friction] = 0.0; // the seed's frictionless disc
    // The slack's sensitivity is taken by a relative step: a fit of it starts inside its range.
    if (options.model == ModelVariant::Slack && !(base[Param::CompressionSlack] > 0)) base[Param::CompressionSlack] = kSlackFitStart;
    base = params_for_record(base, records.front());
    state->ev.emplace(records, options, vars, base);
    Evaluator& ev = *state->ev;

    Eigen::VectorXd x(n);
    for (int i = 0; i < n; ++i) {
        // A tied coordinate starts at the mean of its parameters' coordinates.
        double c = 0;
        for (Param q : vars[i].params) c += vars[i].to_coord(std::max(base[q], 1e-300));
        x[i] = std::clamp(c / static_cast<double>(vars[i].params.size()), vars[i].lower, vars[i].upper);
    }
    const bool lm = options.method == FitMethod::Sensitivity;
    const int measurement_params = measurement_parameters(records, options);
    const int global = options.global_evaluations > 0 ? options.global_evaluations : (lm ? 0 : 4 * n);
    const int local = options.local_evaluations > 0 ? options.local_evaluations : (lm ? 4 * n + 6 : 8 * n + 8);
    // An upper bound: CRS2 may overrun its budget by a few evaluations, and the
    // mirror check may add a second local stage of half the budget.
    ev.set_planned((options.start ? 1 : 0) + options.scan_evaluations + global + n + 2 + local + 1 + local / 2 + (options.spread_seeds > 0 ? 1 : 0) +
                   (lm && options.shear == ShearHold::Auto ? 1 + kHoldEvaluations : 0) +
                   (options.uncertainty && !lm ? 2 * n : 0));

    bool cancelled = false;
    std::vector<int> bend_vars;
    for (int i = 0; i < n; ++i)
        if (vars[static_cast<std::size_t>(i)].params.front() == Param::BendWarp ||
            vars[static_cast<std::size_t>(i)].params.front() == Param::BendWeft)
            bend_vars.push_back(i);
    bool have_dc = false;
    for (const auto& r : records) have_dc |= std::isfinite(r.drape_coefficient_percent);
    Box box;
    for (const auto& v : vars) box.push_back({v.lower, v.upper});
    try {
        // A given start (a library preset, or the coarse optimum a refit starts from)
        // is a candidate: the fit does not end worse than where it began. (A refit
        // whose scan and small budget got lost ended at chi2 108 where its start,
        // the coarse optimum, explained the record.)
        //
        // Warm states given (the tied refit, from the free optimum's drapes): the
        // start is also re-solved from them, after its cold drapes (the best of the
        // two is kept; the scan reads the last). Each drape's rest state is one of
        // several with the same fold count, and which one it comes to depends on its
        // path: the free fit's chi2 is that of the states its warm steps carried
        // along, while cold drapes at the same parameters can rest elsewhere (the
        // isotropic synthetic record of tst_est_fit, grid 25: chi2 40.2 cold at the
        // free optimum against 11.7 warm, so the tie "cost" 21 from cold drapes).
        if (options.start) ev.objective(x, Start::Cold, Stage::Start);
        if (options.start && warm) ev.objective_from(x, *warm, Stage::Start);
        if (have_dc && !bend_vars.empty() && options.scan_evaluations > 0)
            scan_bending(ev, vars, bend_vars, options.scan_evaluations, x, box, lm);
    } catch (const CancelledFit&) {
        cancelled = true;
    }
    const Start global_start = options.warm_global ? Start::Best : Start::Cold;
    const Start local_start = options.warm_local ? Start::Best : Start::Cold;
    if (!cancelled && global > 0) cancelled = run_stage(nlopt::GN_CRS2_LM, ev, vars, x, global, global_start, Stage::Global, options.seed, box);
    if (lm) {
        // Within the scan's fold branch the objective is smooth: Levenberg-Marquardt
        // on the exact sensitivities, warm from the best rest states, in the whole
        // fit range (the scan's box only steered the derivative-free search).
        if (!cancelled) cancelled = levenberg_marquardt(ev, vars, x, {}, local, Stage::Local, local_start);
    } else if (!cancelled) {
        cancelled = run_stage(nlopt::LN_BOBYQA, ev, vars, x, local, local_start, Stage::Local, options.seed + 1);
    }
    if (!cancelled) cancelled = mirror_check(ev, vars, bend_vars, x, local / 2, local_start, options.seed + 2, lm);
    if (!cancelled && lm)
        cancelled = hold_unseen_shear(ev, vars, options, measurement_params, kHoldEvaluations, local_start, out.shear_hold);
    if (!cancelled && options.spread_seeds > 0 && ev.best_x().size() == n) {
        try {
            // The drapes from flat of the report's cold_* columns wait for the
            // caller's choice of the run it keeps (a tied or refined refit may
            // replace this one): deferred below.
            ev.calibrate_spread(ev.best_x(), options.spread_seeds);
            ev.report(Stage::Spread);
        } catch (const CancelledFit&) {
            cancelled = true;
        }
    }
    out.cancelled = cancelled;
    if (ev.best_x().size() != n) { // cancelled before the first evaluation finished
        out.params = base;
        out.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
        return out;
    }
    x = ev.best_x();
    const Evaluation best = ev.best();
    out.best_coords = x;
    out.params = ev.params_at(x);
    out.residuals = best.terms;
    out.chi2 = best.chi2;
    out.dof = fit_dof(best.terms, n + measurement_params);

    // ---- uncertainty, estimates and the per-record comparison ----------------
    const Eigen::MatrixXd J_opt = estimate_parameters(out, ev, records, options, x, best, cancelled);
    compare_records(out, ev, records, options, best, cancelled);
    analyse_optimum(out, J_opt, n + measurement_params);
    // The drapes from flat and the effect tests, for the caller to run on the
    // result it keeps.
    deferred = defer_after_search(state, out, x, best, J_opt);
    record_work(out, ev, t0);
    return out; // fit_fabric reports the whole fit's "done"
}

} // namespace detail

/// The free fit, refined where grid-bound, and its tied refit where warp and
/// weft are not separated (fit_fabric reports the one "done").
static FitResult fit_runs(const std::vector<MeasuredDrape>& records, const FitOptions& options)
{
    if (options.refine_grid != 0 && (options.refine_grid <= options.grid || options.refine_grid > 200))
        throw ParameterError("fit: refine grid = " + std::to_string(options.refine_grid) + " must be 0 (off) or above the grid " +
                             std::to_string(options.grid) + " and at most 200");
    if (options.flat_check_grid < 0 || options.flat_check_grid > 200)
        throw ParameterError("fit: flat check grid = " + std::to_string(options.flat_check_grid) +
                             " must be 0 (off) or a grid of at most 200 (not above the fitted grid: not run)");
    if (!(options.typical_shear_N_m > 0) || !std::isfinite(options.typical_shear_N_m))
        throw ParameterError("fit: typical shear = " + std::to_string(options.typical_shear_N_m) + " N/m must be a finite stiffness > 0");
    if (!(options.typical_bending_anisotropy >= 1) || !std::isfinite(options.typical_bending_anisotropy))
        throw ParameterError("fit: typical bending anisotropy = " + std::to_string(options.typical_bending_anisotropy) +
                             " must be a finite factor >= 1");
    DeferredEffects free_effects;
    FitResult free = fit_with_refinement(records, options, free_effects);
    auto& a = free.anisotropy;
    // Only the kept run's candidate effects are tested (its tests run last).
    auto finish = [&options](FitResult& kept, const DeferredEffects& effects, const std::string& prefix) {
        if (effects && !kept.cancelled) effects(kept, options, prefix);
        else if (effects && options.effects) // cancelled: the cancel flag stops them; the report says so
            kept.residual.unexplained = "candidate effects not tested: the fit was cancelled";
        return std::move(kept);
    };
    if (options.bending != BendingTie::Auto || free.cancelled || !a.assessed) return finish(free, free_effects, "");
    if (anisotropy_stands(free, options)) return finish(free, free_effects, "");
    DeferredEffects tied_effects;
    FitResult kept = tie_bendings(records, options, free, tied_effects);
    return kept.anisotropy.tied ? finish(kept, tied_effects, "tie ") : finish(kept, free_effects, "");
}

FreeStripCheck free_strip_check(const MeasuredDrape& m, double dc, const cloth::FabricParams& p)
{
    FreeStripCheck c;
    if (!(dc > 0 && dc < 100) || !(m.areal_density > 0) || !(m.disc_diameter > 0) || !(m.disc_diameter < m.sample_diameter)) return c;
    c.bound_Nm = cloth::free_strip_bending_bound(m.sample_diameter, m.disc_diameter, m.areal_density, dc);
    const double warp = p[cloth::Param::BendWarp], weft = p[cloth::Param::BendWeft];
    if (!(warp > 0 && weft > 0)) return c;
    c.preset_dc_percent = 0.5 * (cloth::free_strip_drape_coefficient(m.sample_diameter, m.disc_diameter, m.areal_density, warp) +
                                 cloth::free_strip_drape_coefficient(m.sample_diameter, m.disc_diameter, m.areal_density, weft));
    c.below = c.preset_dc_percent > dc + kFreeStripMarginPoints;
    return c;
}

void check_free_strips(FitResult& out)
{
    for (RecordFit& rf : out.records) {
        const FreeStripCheck c = free_strip_check(rf.measured, rf.measured_features.drape_coefficient_percent, out.params);
        rf.free_strip_bound_Nm = c.bound_Nm;
        rf.free_strip_preset_dc_percent = c.preset_dc_percent;
        rf.below_free_strips = c.below;
    }
}

FitResult fit_fabric(const std::vector<MeasuredDrape>& records, const FitOptions& options)
{
    FitResult out = fit_runs(records, options);
    if (!out.cancelled) check_free_strips(out);
    if (options.progress) {
        FitProgress p;
        p.stage = to_string(Stage::Done);
        p.stage_id = Stage::Done;
        p.search = false;
        p.evaluation = p.planned = out.evaluations;
        p.best_chi2 = out.chi2;
        p.simulations = out.simulations;
        p.elapsed_s = out.wall_seconds;
        options.progress(p);
    }
    return out;
}

} // namespace drape::estimate
