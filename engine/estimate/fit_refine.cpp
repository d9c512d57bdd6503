// The grid refinement (docs/decisions/0004-fit-grid-41.md): a grid-bound optimum
// - a fitted bending length below the mesh spacing - refitted on the finer grid,
// and which of the two runs the fit keeps.
#include "engine/estimate/detail/pipeline.hpp"

#include <cstdio>
#include <utility>

namespace drape::estimate::detail {

FitResult fit_with_refinement(const std::vector<MeasuredDrape>& records, const FitOptions& options, DeferredEffects& effects)
{
    DeferredEffects coarse_effects;
    FitResult coarse = fit_at_grid(records, options, coarse_effects);
    if (!coarse.grid_bound || options.refine_grid == 0 || coarse.cancelled) {
        effects = std::move(coarse_effects);
        return coarse;
    }
    // The coarse optimum's bending is shorter than the mesh spacing: the mesh did
    // part of the bending's work, so the preset would not carry over. Fit again on
    // the finer grid, from the coarse values (the scan re-finds the bending's decade).
    FitOptions fine = options;
    fine.grid = options.refine_grid;
    fine.start = coarse.params;
    fine.progress = continued_progress(options, "refine ", coarse);
    DeferredEffects fine_effects;
    FitResult out = fit_at_grid(records, fine, fine_effects);
    FitResult::Refinement ref;
    ref.from_grid = options.grid;
    ref.to_grid = fine.grid;
    ref.coarse_chi2 = coarse.chi2;
    ref.coarse_dof = coarse.dof;
    ref.fine_chi2 = out.chi2;
    ref.fine_dof = out.dof;
    // The finer mesh is the more faithful model, so its fit replaces the coarse
    // one - unless it leaves a residual beyond the noise where the coarse one did
    // not (the finer search got lost, or the record's fit leaned on the coarse
    // mesh): then the coarse preset is kept, grid-bound and saying so.
    // (The residual's own tests, not the candidate effects': one candidate's alarm
    // among a dozen tests is not a reason to keep a grid-bound preset.)
    ref.adopted = !out.cancelled && (!out.residual.exceeds_noise_by_residual || coarse.residual.exceeds_noise_by_residual);
    char buf[300];
    if (out.cancelled)
        std::snprintf(buf, sizeof buf, "the grid-%d optimum was grid-bound; its refit at grid %d was cancelled, so the grid-%d preset is kept",
                      ref.from_grid, ref.to_grid, ref.from_grid);
    else if (ref.adopted)
        std::snprintf(buf, sizeof buf, "the grid-%d optimum was grid-bound; refitted at grid %d (chi2 %.1f / %d there, %.1f / %d at grid %d)",
                      ref.from_grid, ref.to_grid, ref.fine_chi2, ref.fine_dof, ref.coarse_chi2, ref.coarse_dof, ref.from_grid);
    else
        std::snprintf(buf, sizeof buf,
                      "the grid-%d optimum was grid-bound, but the refit at grid %d left a residual beyond the noise (chi2 %.1f / %d) "
                      "where grid %d did not (%.1f / %d): kept the grid-%d preset, which holds at that mesh density only",
                      ref.from_grid, ref.to_grid, ref.fine_chi2, ref.fine_dof, ref.from_grid, ref.coarse_chi2, ref.coarse_dof, ref.from_grid);
    ref.reason = buf;
    FitResult kept = combine_runs(coarse, out, ref.adopted, "refine ");
    kept.options.refine_grid = options.refine_grid;
    kept.refinement = ref;
    if (ref.adopted && fine_effects)
        effects = [f = std::move(fine_effects)](FitResult& k, const FitOptions& o, const std::string& p) { f(k, o, p + "refine "); };
    else
        effects = std::move(coarse_effects);
    return kept;
}

} // namespace drape::estimate::detail
