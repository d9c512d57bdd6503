// After a run's search, on the result the caller keeps: the preset's drapes from
// flat at the optimum (docs/decisions/0018-flat-check-grid-61.md), then the effect
// tests and the flat calibration, their work counted into the kept result's.
#include "engine/estimate/detail/pipeline.hpp"

#include <utility>

namespace drape::estimate::detail {

void set_from_flat(RecordFit& rf, const Evaluator& ev, std::size_t r)
{
    if (r < ev.cold_features().size() && ev.cold_seeds(r) > 0) {
        rf.cold_seeds = ev.cold_seeds(r);
        rf.cold_features = ev.cold_features()[r];
        rf.cold_dc_error_percent = rf.cold_features.drape_coefficient_percent - rf.measured_features.drape_coefficient_percent;
        rf.cold_node_error = rf.cold_features.node_count - rf.measured_features.node_count;
    }
    if (const Evaluator::FineDrape* f = ev.cold_fine(r)) {
        rf.cold_fine_grid = ev.options().flat_check_grid;
        rf.cold_fine_converged = f->at_rest;
        rf.cold_fine_features = f->features;
        rf.cold_fine_dc_error_percent = f->features.drape_coefficient_percent - rf.measured_features.drape_coefficient_percent;
        rf.cold_fine_node_error = f->features.node_count - rf.measured_features.node_count;
    }
}

void set_preset(RecordFit& rf, const DrapeFeatures& f, const std::vector<cloth::DrapeResult>& sims, bool moved)
{
    rf.preset_moved = moved;
    rf.preset_features = f;
    rf.preset_converged = true;
    for (const auto& sim : sims) rf.preset_converged = rf.preset_converged && sim.status.converged();
    rf.preset_dc_error_percent = f.drape_coefficient_percent - rf.measured_features.drape_coefficient_percent;
    rf.preset_node_error = f.node_count - rf.measured_features.node_count;
}

namespace {

/// What a run's optimum hands to the work after its search.
struct AfterSearch {
    std::vector<FitVariable> vars;
    Eigen::VectorXd x;
    Evaluation best;
    Eigen::MatrixXd J_opt;
    bool from_flat = false, effects = false, calibrate = false;
};

/// The work after the search on `kept`, on the run's evaluator: the drapes from
/// flat, the effect tests, the flat calibration; progress and trace continue the
/// kept result's counts and time, and the work is added to it.
void run_after_search(GridRunState& state, const AfterSearch& a, FitResult& kept, const FitOptions& caller, const std::string& prefix)
{
    Evaluator& e = *state.ev;
    const WorkCounters work0 = e.work();
    const std::size_t trace0 = e.trace().size();
    // Progress and trace continue the kept result's counts and time (this
    // run's evaluator may be behind it: a run after it was not kept).
    FitResult before;
    static_cast<WorkCounters&>(before) = kept - work0;
    state.options.progress = continued_progress(caller, prefix, before, false);
    try {
        if (a.from_flat) {
            e.draw_from_flat(a.x, Stage::FromFlat);
            for (std::size_t r = 0; r < kept.records.size(); ++r) set_from_flat(kept.records[r], e, r);
        }
        if (a.effects) test_effects(e, a.vars, a.x, a.best, a.J_opt, kept);
        if (a.from_flat && a.calibrate) calibrate_from_flat(e, a.vars, a.x, a.J_opt, kept);
    } catch (const CancelledFit&) {
        kept.cancelled = true;
    }
    state.options.progress = nullptr;
    for (std::size_t k = trace0; k < e.trace().size(); ++k) {
        FitTraceEntry t = e.trace()[k];
        t.evaluation += before.evaluations;
        t.elapsed_s += before.wall_seconds;
        t.stage = prefix + t.stage;
        kept.trace.push_back(std::move(t));
    }
    kept += e.work() - work0;
}

} // namespace

DeferredEffects defer_after_search(std::shared_ptr<GridRunState> state, const FitResult& out, const Eigen::VectorXd& x,
                                   const Evaluation& best, const Eigen::MatrixXd& J_opt)
{
    const FitOptions& options = state->options;
    // The drapes from flat of the report's cold_* columns wait for the caller's
    // choice of the run it keeps.
    const bool from_flat = options.spread_seeds > 0 && options.random_start_seeds > 0;
    if (!((options.effects || from_flat) && !out.cancelled)) return nullptr;
    AfterSearch a{out.variables, x, best, J_opt, from_flat, options.effects, options.flat_calibration};
    return [state = std::move(state), a = std::move(a)](FitResult& kept, const FitOptions& caller, const std::string& prefix) {
        run_after_search(*state, a, kept, caller, prefix);
    };
}

} // namespace drape::estimate::detail
