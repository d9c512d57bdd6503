#pragma once
// The fit's pipeline below the orchestrator (fit.cpp, which runs it in the order
// of docs/estimate.md "Stages in order"): one run of the fit at one grid, the runs
// that replace it (grid refinement, the bending tie), and the stages after a run's
// search, each defined in the file named at it. Internal to the estimate layer.
#include "engine/estimate/detail/evaluator.hpp"

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace drape::estimate::detail {

/// Largest rise of chi2 (scaled) at which the tied fit is kept (BendingTie::Auto),
/// and the held shear (ShearHold::Auto).
inline constexpr double kTieChi2 = 9.0;

/// The held shear's refit (ShearHold::Auto): Levenberg-Marquardt evaluations after
/// the held point's own - a re-balance of the others against the held shear, not a
/// new search (with n + 2 = 5, DL-A05's refit went on into another, 20-fold
/// anisotropic basin and its fit took 70 s).
inline constexpr int kHoldEvaluations = 2;

// ---- runs of the fit (fit_runs.cpp) ----------------------------------------

/// The caller's progress callback for one run of a fit that may run again
/// ("refine ", "tie " prefix every stage of a run on behalf of the first): the
/// counts continue from the runs before it (`before`: their evaluations,
/// simulations, time), so the bar does not fall back to a few per cent with the
/// whole fit's elapsed time behind it (the second run's first line said "about
/// 49 min left" for a fit that ended a minute later). A run reports no "done" of
/// its own: fit_fabric reports the fit's one. Empty when there is no callback.
std::function<void(const FitProgress&)> continued_progress(const FitOptions& options, std::string prefix, const FitResult& before,
                                                           bool search = true);


/// `kept` (one of two fits of the same records, run one after the other) with the
/// counts and time of both and one trace in the order they ran, the second's
/// stages prefixed.
FitResult combine_runs(const FitResult& first, const FitResult& second, bool keep_second, const std::string& prefix);

/// A run's work as its evaluator counted it: evaluations, simulations,
/// factorisations, the trace and the wall time since t0.
void record_work(FitResult& out, const Evaluator& ev, Clock::time_point t0);

/// A run's candidate-effect tests, kept for later: they cost a re-solve per
/// switch effect and seed (10 drapes on one record), and a run that a refit
/// replaces (the grid-bound coarse run, the free run before its tie) needs none.
/// Applied to the result kept from that run (FitResult as combine_runs made it):
/// adds the tests' verdicts and their work and trace. Empty: nothing to run.
/// `options`: the caller's (its progress callback; the counts continue the kept
/// result's); `prefix`: the kept run's stage prefix ("tie ", "refine ", "").
using DeferredEffects = std::function<void(FitResult&, const FitOptions&, const std::string& prefix)>;

/// What a run's deferred work needs alive after fit_at_grid returns: the
/// Evaluator holds references to the records and options it was made with.
struct GridRunState {
    std::vector<MeasuredDrape> records;
    FitOptions options;
    std::optional<Evaluator> ev;
};

/// One fit at options.grid: scan, global, local, mirror, spread, uncertainty;
/// its candidate-effect tests (options.effects) are handed back through
/// `deferred` (empty when there are none to run) for the caller to run on the
/// result it keeps. `warm`: rest states ([record][seed], on options.grid with
/// options.seed's seeds) the given start is also draped from; nullptr: from flat only.
/// (fit.cpp)
FitResult fit_at_grid(const std::vector<MeasuredDrape>& records_in, const FitOptions& options_in, DeferredEffects& deferred,
                      const std::vector<std::vector<cloth::Positions>>* warm = nullptr);

/// fit_at_grid, and again on options.refine_grid when the optimum is grid-bound
/// (docs/decisions/0004-fit-grid-41.md). (fit_refine.cpp)
FitResult fit_with_refinement(const std::vector<MeasuredDrape>& records, const FitOptions& options, DeferredEffects& effects);

// ---- the optimum's estimates (fit_estimates.cpp) ---------------------------

/// The fitted coordinate that sets q alone (-1: none, or q is tied to another).
int sole_variable(const std::vector<FitVariable>& vars, cloth::Param q);

/// Degrees of freedom of a fit: its fitted terms less its fitted parameters, at least 1.
int fit_dof(const std::vector<ResidualTerm>& terms, int parameters);

/// The measurement model's own parameters, fitted with the fabric's: a re-centred
/// stack's axis (2 per record), an untilted one's offset and tilt (4; 2 with one
/// cut). Counted over the record's closed cuts: none, no axis; one depth, an offset.
int measurement_parameters(const std::vector<MeasuredDrape>& records, const FitOptions& options);

/// Whether a residual term enters the linearised tests at the optimum (the
/// effect tests' rows, the matched filters' projection): the smooth fitted
/// terms - the node count has no derivative, a slice's closure is a count of seeds.
bool linearised_term(const ResidualTerm& t);

/// The uncertainty stage at the optimum x (the evaluator's best point `best`) and
/// the estimates of every parameter: the covariance and sigmas (the exact Jacobian
/// with Levenberg-Marquardt, else central differences; not taken when the search
/// was cancelled), the estimates against the mesh's spacing, what the priors
/// decided, a held shear's note and the warp/weft ratio. A cancellation here sets
/// out.cancelled. Returns the whitened exact Jacobian at the optimum (empty: not taken).
Eigen::MatrixXd estimate_parameters(FitResult& out, Evaluator& ev, const std::vector<MeasuredDrape>& records, const FitOptions& options,
                                    const Eigen::VectorXd& x, const Evaluation& best, bool search_cancelled);

/// out.records: per record the measured and simulated features at the optimum,
/// its preset rows (the optimum's until a calibration moves it), its drapes from
/// flat where drawn, and (a search not cancelled) D's sensitivity to each fitted parameter.
void compare_records(FitResult& out, const Evaluator& ev, const std::vector<MeasuredDrape>& records, const FitOptions& options,
                     const Evaluation& best, bool search_cancelled);

/// out.residual: the residual analysis at the optimum, its matched filters
/// against the part the fit cannot absorb (J_opt's linearised rows; none when empty).
void analyse_optimum(FitResult& out, const Eigen::MatrixXd& J_opt, int parameters);

// ---- shear hold (fit_shear.cpp, docs/decisions/0024-shear-hold.md) ---------

/// ShearHold::Auto on the search's optimum (the evaluator's best point): the
/// shear's 95 % interval from the exact Jacobian there (the search's sigmas,
/// before the spread calibration, which only widens it); open-ended - running into
/// a fit bound, or the shear at one - the shear is moved to
/// options.typical_shear_N_m, the other coordinates
/// refitted by Levenberg-Marquardt with it held (warm from the optimum's rest
/// states, `budget` evaluations: the others re-balance against it), and the held point stays the best point unless
/// its chi2 is above the fitted one's by more than kTieChi2 (scaled by chi2 / dof
/// when that exceeds 1); else the fitted optimum is restored exactly. True when
/// cancelled (the fitted optimum is then restored).
bool hold_unseen_shear(Evaluator& ev, const std::vector<FitVariable>& vars, const FitOptions& options, int measurement_params, int budget,
                       Start from, FitResult::ShearHeld& h);

/// A held shear's estimate (FitResult::shear_hold): role "held", not constrained,
/// the interval it had when fitted in the note.
void mark_held_shear(FitResult& out);

// ---- bending tie (fit_tie.cpp, docs/decisions/0010-bending-tie.md) ---------

/// The free fit's warp/weft bending ratio and its 95 % interval from the
/// covariance of the two log10 coordinates (FitResult::Anisotropy).
void assess_anisotropy(FitResult& out);

/// FitResult::Anisotropy::setups_confirming: per set-up (records of one specimen
/// and disc diameter), the log10 warp/weft ratio its rows alone give - one
/// Gauss-Newton step from the joint optimum on those rows and the prior rows (which
/// keep the other directions bounded), with its 95 % interval from the same
/// information - and whether that interval lies on the joint ratio's side of 1.
void confirm_anisotropy_by_setups(FitResult& out, const Evaluator& ev, const std::vector<MeasuredDrape>& records, const Eigen::MatrixXd& J,
                                  const Evaluation& best);

/// BendingTie::Auto on the free fit: true when its warp/weft ratio stands as
/// fitted - within the typical factor, or beyond it, separated by the data and
/// confirmed by two set-ups (free.anisotropy.reason says which); false: it is to
/// be tested tied (tie_bendings).
bool anisotropy_stands(FitResult& free, const FitOptions& options);

/// The free fit refitted with one bending for warp and weft and the run kept of
/// the two (FitResult::anisotropy says which and why): the tied run's deferred
/// work in `tied_effects`.
FitResult tie_bendings(const std::vector<MeasuredDrape>& records, const FitOptions& options, const FitResult& free,
                       DeferredEffects& tied_effects);

// ---- after the search: drapes from flat (fit_flat.cpp) ---------------------

/// Record r's drapes from flat (cold_*), where the evaluator drew them.
void set_from_flat(RecordFit& rf, const Evaluator& ev, std::size_t r);

/// Record rf's preset_* rows: the seed-averaged features `f` of `sims`, draped as
/// the fit drapes; `moved`: at a preset the calibration moved off the optimum.
void set_preset(RecordFit& rf, const DrapeFeatures& f, const std::vector<cloth::DrapeResult>& sims, bool moved);

/// The run's work after its search, for the caller to run on the result it keeps
/// (a tied or refined refit may replace this run): the drapes from flat at the
/// optimum x, the effect tests and the flat calibration, as the run's options ask.
/// Empty when there is none (or the run was cancelled).
DeferredEffects defer_after_search(std::shared_ptr<GridRunState> state, const FitResult& out, const Eigen::VectorXd& x,
                                   const Evaluation& best, const Eigen::MatrixXd& J_opt);

// ---- effect tests (fit_effects.cpp, docs/decisions/0006-effect-tests.md) ---

/// The candidate effects against the residual at the optimum:
/// engine-made signatures, matched filter and likelihood ratio of the refit with
/// each effect freed, the best parameter effect verified by a drape, the named
/// effect or where the residual is unexplained. J: the whitened Jacobian of the
/// fitted coordinates at x (taken here when empty).
void test_effects(Evaluator& ev, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x, const Evaluation& best,
                  Eigen::MatrixXd J, FitResult& out);

// ---- flat calibration (fit_calibration.cpp, docs/decisions/0020-flat-calibration.md)

/// FitOptions::flat_calibration on the kept result, after its drapes from flat at
/// the optimum x: the preset moved until, draped from flat, it gives the records'
/// fold count and D (FitResult::FlatCalibration). Either:
/// - fold count off by more than 1 (fit_calibration_folds.cpp): a step of the
///   bendings (warp/weft ratio kept) along the contours' profile - the other fitted
///   coordinates follow to where the linearised contours are least for that bending -
///   of 1, then 2 sigma of the profile, softer when the drapes lay too few folds,
///   screened on the fit grid's drapes; one bending scale step for D on the same
///   drapes; then the finer grid's drape; kept when all of them lay the count within
///   1, are closer to the record, and gain more than the contours' scaled linearised
///   chi2 loses; or
/// - fold count within 1: both bendings scaled by one factor until the mean D from
///   flat is within the D channel's sigma (at most two steps).
/// The contour fit's optimum stays the search's result (residuals, chi2,
/// intervals); the preset (`params`), its estimates and the records' drapes from
/// flat become the calibrated ones; where the preset moved, it is draped as the
/// fit drapes (RecordFit::preset_*). Cancelled part-way: the optimum and its
/// drapes are kept (cancelled at that last step: the moved preset, with its
/// preset_* rows NaN), the reason says so, and the cancellation goes on to the caller.
void calibrate_from_flat(Evaluator& ev, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x, const Eigen::MatrixXd& J_opt,
                         FitResult& kept);

} // namespace drape::estimate::detail
