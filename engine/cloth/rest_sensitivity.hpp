#pragma once
// Sensitivity of a rest state to the fabric's parameters: at rest the
// net force f(x, p) = 0, so along a change of a parameter p the rest state moves
// by dx/dp = H^-1 df/dp, with H = -df/dx the Hessian of the potential energy that
// the static solver factorises anyway. One factorisation and one back-substitution
// per parameter give the derivative of every vertex, hence of every drape metric,
// without another drape.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/params.hpp"
#include "engine/cloth/system.hpp"

#include <string>
#include <vector>

namespace drape::cloth {

struct RestSensitivity {
    Param param;
    /// d x / d p per vertex [m per unit of the parameter], with the turn about the
    /// pedestal axis removed (the drapemeter's rest states are a family turned
    /// about it: a neutral direction of H that no parameter moves along).
    Positions dx;
    /// Relative residual of the linear solve, |H dx - df/dp| / |df/dp|.
    double solve_residual = 0;
};

struct RestSensitivityOptions {
    /// Relative step of the parameter for df/dp (central difference of the force
    /// at fixed positions: no drape, no solve; the force is smooth in every
    /// parameter, so this is exact to ~step^2).
    double relative_step = 1e-4;
};

/// The sensitivities of the drapemeter rest state `rest` (positions of the
/// system make_drape_system(fabric, setup, mopt) builds, at rest: relative
/// residual well below the parameter's effect, e.g. 1e-8) to each of `params`.
/// Throws ParameterError when `rest` does not fit the mesh, a parameter is
/// a damper (it does not move a rest state) or its value is 0 (no relative
/// step), and Error when the Hessian at `rest` is not positive definite (not
/// a stable rest state).
std::vector<RestSensitivity> rest_sensitivities(const Material& fabric, const DrapeSetup& setup, const Positions& rest,
                                                const std::vector<Param>& params, const ModelOptions& mopt = {},
                                                const RestSensitivityOptions& opt = {});

/// The rest state's responses to parameters and to changes of the set-up, on
/// one factorisation of the Hessian. A changed set-up (the same mesh: the
/// specimen laid off centre, an uneven weight - DrapeSetup::specimen_offset,
/// density_gradient) adds the force f(rest; changed) - f(rest; setup) at fixed
/// positions; its response is H^-1 of that force, first order in the change
/// (exact for those two: the force is linear in them).
struct RestResponses {
    std::vector<RestSensitivity> params; ///< as rest_sensitivities
    std::vector<Positions> setups;       ///< dx per changed set-up [m for the whole change], the turn removed
    std::vector<double> setup_residuals; ///< relative residuals of their solves
};
RestResponses rest_responses(const Material& fabric, const DrapeSetup& setup, const Positions& rest, const std::vector<Param>& params,
                             const std::vector<DrapeSetup>& changed_setups, const ModelOptions& mopt = {},
                             const RestSensitivityOptions& opt = {});

/// The drape metrics' derivatives at the rest state: the shadow's drape
/// coefficient and the hem's mean height along dx/dp (a central difference of the
/// shared metric code along x +- e dx/dp, e = 1e-3 of the parameter).
struct DrapeMetricSensitivity {
    Param param;
    double value;                      ///< the parameter's value at the rest state
    double d_drape_coefficient_percent; ///< dD/dp [% per unit of the parameter]
    double d_hem_mean_z;               ///< d(mean hem height)/dp [m per unit of the parameter]
    double solve_residual;             ///< of the linear solve (RestSensitivity)
};
std::vector<DrapeMetricSensitivity> drape_metric_sensitivities(const Material& fabric, const DrapeSetup& setup, const Positions& rest,
                                                               const std::vector<Param>& params, const ModelOptions& mopt = {});

/// The same positions turned about the pedestal axis (z) by the infinitesimal
/// rotation: (-y, x, 0) per vertex. The neutral direction the sensitivities are
/// made orthogonal to.
Positions axis_turn(const Positions& x);

} // namespace drape::cloth
