#pragma once
// The search stages of a fit, each on the evaluator (evaluator.hpp): the scan
// of a common bending for the measured D, NLopt's global and local stages, and
// the warp/weft mirror check. Internal to the estimate layer.
#include "engine/estimate/detail/evaluator.hpp"

#include <nlopt.hpp>

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace drape::estimate::detail {

/// Search box of each coordinate (lower, upper) in search coordinates.
using Box = std::vector<std::pair<double, double>>;

/// One NLopt stage from x within `box` (the variables' bounds when empty).
/// Leaves x at the best point so far. A simulation error (drape::Error) thrown
/// inside the objective is rethrown here, not swallowed; returns true when the
/// fit was cancelled.
bool run_stage(nlopt::algorithm alg, Evaluator& ev, const std::vector<FitVariable>& vars, Eigen::VectorXd& x, int maxeval,
               Start from, Stage stage, std::uint64_t seed, const Box& box = {});

/// Stage 0, "scan": D grows monotonically with bending stiffness, so a root
/// search on a common bending (warp = weft) for the measured D finds the right
/// decade: from the start value in steps of a decade until D is bracketed, then
/// regula falsi (Illinois) in log10 of the bending, stopping within 0.5 points
/// of D, at most `budget` evaluations. Cold starts, so each seed's fold pattern
/// is the one a drop at that stiffness forms (a warm chain from a limp start
/// kept 12 folds up to stiff fabrics). Sets the bending coordinates of x to the
/// best point and narrows their box to +-0.7 decades around it. `newton`: the
/// steps are safeguarded Newton steps on the exact slope of D (the drape's
/// rest-state sensitivities), usually 2-3 drapes instead of 5-6. Throws CancelledFit.
void scan_bending(Evaluator& ev, const std::vector<FitVariable>& vars, const std::vector<int>& bend_vars, int budget,
                  Eigen::VectorXd& x, Box& box, bool newton = false);

/// Levenberg-Marquardt on the whitened residuals from the best point so far
/// (evaluating x first when there is none): each iteration linearises the rest
/// states with their exact sensitivities (Evaluator::jacobian), solves the
/// damped normal equations (J^T J + lambda diag(J^T J)) d = -J^T r inside `box`
/// (at most half a decade per step on log scales) and drapes the step warm from
/// the best rest states; accepted when chi2 falls (lambda shrinks by the gain
/// ratio), else lambda grows. Stops when a step gains less than 0.2 in chi2 or
/// moves less than `xtol` per coordinate, or after `budget` evaluations. Leaves
/// x at the best point; returns true when cancelled. `from`: where the trial
/// drapes start (Start::Best, warm, by default; Cold with --cold-local).
bool levenberg_marquardt(Evaluator& ev, const std::vector<FitVariable>& vars, Eigen::VectorXd& x, const Box& box, int budget,
                         Stage stage, Start from = Start::Best);

/// The profile of the bendings in a linearised chi2 |w + J dx|^2 (only the rows
/// where `rows` is set): for a step of every bending coordinate (`bend`) by one
/// together, the other coordinates' step that keeps the chi2 least - where the
/// other fitted parameters go when the bendings are held at another value. Returns
/// that direction (1 at the bending coordinates) and, in `curvature`, |J dir|^2 over
/// the rows: the chi2's rise per (decade of bending)^2 along it. Other coordinates
/// the rows do not see stay (0). Used by the calibration from flat
/// (fit_calibration_folds.cpp).
Eigen::VectorXd profile_direction(const Eigen::MatrixXd& J, const std::vector<char>& rows, const std::vector<int>& bend, double& curvature);

/// Mirror check: D and the node count do not change when warp and weft swap;
/// only the signed cos 2theta of the contours tells which axis is stiffer, and
/// it is weak against the fold noise, so a local stage can end in the mirror
/// image of the optimum. One evaluation at the swapped point; a second local
/// stage (`local` evaluations) from there when it is better. Returns true when cancelled.
/// `lm` runs the second local stage as levenberg_marquardt (else BOBYQA).
bool mirror_check(Evaluator& ev, const std::vector<FitVariable>& vars, const std::vector<int>& bend_vars, Eigen::VectorXd& x,
                  int local, Start from, std::uint64_t seed, bool lm = false);

} // namespace drape::estimate::detail
