#pragma once
// What a fit knows about its parameters: the covariance of the search
// coordinates from the Jacobian of the smooth whitened residuals at the
// optimum, and one estimate (role, value, 95 % interval, notes) per parameter
// of the table. Internal to the estimate layer.
#include "engine/estimate/detail/evaluator.hpp"

#include <vector>

namespace drape::estimate::detail {

/// Central differences of the smooth, fitted whitened residuals at x (warm
/// re-solves) -> cov = s^2 (J^T J)^-1 with s^2 = max(1, chi2/dof), into
/// out.covariance and out.correlation. Returns the 1-sigma of each search
/// coordinate (infinite along directions the data does not see). Throws CancelledFit.
std::vector<double> coordinate_sigmas(Evaluator& ev, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x,
                                      const Evaluation& best, FitResult& out);

/// The same from a Jacobian of the whitened residual terms (any rows: zero
/// rows for terms left out, e.g. Evaluator::jacobian, add nothing).
std::vector<double> sigmas_from_jacobian(const Eigen::MatrixXd& J_terms, FitResult& out);

/// How near a fit bound a coordinate counts as at it: 0.05 decade on a log scale,
/// 1 % of the range on a linear one.
double bound_edge(const FitVariable& v);
/// Whether search coordinate c of v is at a fit bound (within bound_edge).
bool at_fit_bound(const FitVariable& v, double c);
/// Whether the interval c +- half of v reaches a fit bound (within bound_edge) - the
/// data leave that side open; a non-finite half always does.
bool interval_reaches_bound(const FitVariable& v, double c, double half);

/// Fills out.estimates (every parameter of the table) and out.grid_bound from
/// the optimum x and the coordinate sigmas. `mesh_spacing_m` is the fit's grid
/// spacing: a fitted bending whose bending length is below it is grid-bound.
/// `rim_spacing_m`: the mesh's spacing where the cloth bends over the pedestal's
/// rim (the grid's; the rings' refined band), against which the rim bend
/// sqrt(B / T) is noted (T from `rim_lever_m`); 0 = mesh_spacing_m.
void parameter_estimates(FitResult& out, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x,
                         const std::vector<double>& sigma, bool uncertainty_computed, double mesh_spacing_m,
                         double rim_lever_m = 0, double rim_spacing_m = 0);

} // namespace drape::estimate::detail
