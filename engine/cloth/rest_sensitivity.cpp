#include "engine/cloth/rest_sensitivity.hpp"
#include "engine/cloth/solver_detail.hpp"

#include "engine/cloth/sparse_cholesky.hpp"
#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <cmath>

namespace drape::cloth {

Positions axis_turn(const Positions& x)
{
    Positions t(x.rows(), 3);
    for (int i = 0; i < x.rows(); ++i) t.row(i) << -x(i, 1), x(i, 0), 0.0;
    return t;
}

namespace {

using detail::flat;

/// The force at fixed positions of the drape scene built with parameters `p`.
Positions forces_with(const Material& p, const DrapeSetup& setup, const ModelOptions& mopt, const Positions& x)
{
    auto sys = make_drape_system(p, setup, mopt);
    Positions f;
    sys->conservative_forces(x, f);
    for (int i = 0; i < sys->vertex_count(); ++i)
        if (sys->pinned(i)) f.row(i).setZero();
    return f;
}

} // namespace

std::vector<RestSensitivity> rest_sensitivities(const Material& fabric, const DrapeSetup& setup, const Positions& rest,
                                                const std::vector<Param>& params, const ModelOptions& mopt,
                                                const RestSensitivityOptions& opt)
{
    return rest_responses(fabric, setup, rest, params, {}, mopt, opt).params;
}

RestResponses rest_responses(const Material& fabric, const DrapeSetup& setup, const Positions& rest, const std::vector<Param>& params,
                             const std::vector<DrapeSetup>& changed_setups, const ModelOptions& mopt, const RestSensitivityOptions& opt)
{
    if (fabric.grid_springs)
        throw ParameterError("rest sensitivities: a seed-19 preset's grid springs are not continuum parameters (use its continuum equivalent)");
    if (!(opt.relative_step > 0 && opt.relative_step < 0.1))
        throw ParameterError("rest sensitivities: relative step = " + format_value(opt.relative_step) + " must be in (0, 0.1)");
    for (Param p : params) {
        const ParamSpec& sp = spec(p);
        if (!sp.affects_statics)
            throw ParameterError("rest sensitivities: " + std::string(sp.key) + " is a damper; it does not move a rest state");
        if (!(std::abs(fabric.params[p]) > 0))
            throw ParameterError("rest sensitivities: " + std::string(sp.key) + " = 0 has no relative step (set it to a value first)");
    }
    auto sys = make_drape_system(fabric, setup, mopt);
    const int n = sys->vertex_count();
    if (rest.rows() != n || !rest.allFinite())
        throw ParameterError("rest sensitivities: the rest state has " + std::to_string(rest.rows()) + " vertices (finite: " +
                             (rest.allFinite() ? "yes" : "no") + "), the drape mesh " + std::to_string(n));

    // H = -df/dx, the exact Hessian (no projection: at a stable rest state it is
    // positive semi-definite). Its one neutral direction, the turn about the axis,
    // gets a tiny shift; the solution is then made orthogonal to it.
    HessianAssembler H(*sys);
    H.assemble(rest, Eigen::VectorXd(), 0.0, HessianAssembler::Projection::None);
    detail::SpMat As = H.matrix(); // upper triangle; shifted in place below
    double max_diag = 0;
    for (int k = 0; k < As.rows(); ++k) max_diag = std::max(max_diag, As.coeff(k, k));
    const double shift = 1e-10 * max_diag;
    for (int k = 0; k < As.rows(); ++k) As.coeffRef(k, k) += shift;
    bool reused = false;
    auto llt = detail::take_analysed(As, reused);
    llt->factorize(As);
    if (llt->info() != Eigen::Success)
        throw Error("rest sensitivities: the Hessian at the given state is not positive definite (not a stable rest state)");
    // H x of the unshifted Hessian.
    auto H_times = [&](const Eigen::VectorXd& x) -> Eigen::VectorXd { return As.selfadjointView<Eigen::Upper>() * x - shift * x; };

    const Positions turn = axis_turn(rest);
    const Eigen::VectorXd t = flat(turn) / flat(turn).norm();
    // x = H^-1 b, orthogonal to the turn; the solve's relative residual.
    auto solve = [&](const Positions& force, Positions& dx) {
        const Eigen::VectorXd b = flat(force);
        Eigen::VectorXd x = llt->solve(b);
        x += llt->solve(b - H_times(x)); // one step of refinement against the unshifted H
        x -= t.dot(x) * t;
        dx = Eigen::Map<const Positions>(x.data(), n, 3);
        const double bn = b.norm();
        return bn > 0 ? (H_times(x) - b).norm() / bn : 0.0;
    };
    RestResponses out;
    for (Param p : params) {
        const double v = fabric.params[p], h = opt.relative_step * std::abs(v);
        FabricParams lo = fabric.params, hi = fabric.params;
        lo[p] = v - h;
        hi[p] = v + h;
        RestSensitivity s;
        s.param = p;
        s.solve_residual = solve((forces_with(Material(hi), setup, mopt, rest) - forces_with(Material(lo), setup, mopt, rest)) / (2 * h), s.dx);
        out.params.push_back(std::move(s));
    }
    if (!changed_setups.empty()) {
        const Positions f0 = forces_with(fabric, setup, mopt, rest);
        for (const DrapeSetup& c : changed_setups) {
            if (c.grid != setup.grid || c.mesh != setup.mesh || c.sample_diameter != setup.sample_diameter ||
                (c.mesh == DrapeMesh::Rings && c.disc_diameter != setup.disc_diameter))
                throw ParameterError("rest responses: a changed set-up must keep the mesh (" + std::string(to_string(c.mesh)) + " " +
                                     std::to_string(c.grid) + " on " + format_value(c.sample_diameter * 1e3) + " / " +
                                     format_value(c.disc_diameter * 1e3) + " mm vs " + std::string(to_string(setup.mesh)) + " " +
                                     std::to_string(setup.grid) + " on " + format_value(setup.sample_diameter * 1e3) + " / " +
                                     format_value(setup.disc_diameter * 1e3) + " mm)");
            Positions dx;
            out.setup_residuals.push_back(solve(forces_with(fabric, c, mopt, rest) - f0, dx));
            out.setups.push_back(std::move(dx));
        }
    }
    detail::keep_analysed(std::move(llt), As);
    return out;
}

std::vector<DrapeMetricSensitivity> drape_metric_sensitivities(const Material& fabric, const DrapeSetup& setup, const Positions& rest,
                                                               const std::vector<Param>& params, const ModelOptions& mopt)
{
    const auto sens = rest_sensitivities(fabric, setup, rest, params, mopt);
    auto sys = make_drape_system(fabric, setup, mopt);
    std::vector<DrapeMetricSensitivity> out;
    for (const auto& s : sens) {
        // The metrics along the first-order path x + dp dx/dp (central difference).
        const double v = fabric.params[s.param], e = 1e-3 * std::abs(v);
        sys->x = rest + e * s.dx;
        const DrapeResult up = measure_drape(*sys, setup);
        sys->x = rest - e * s.dx;
        const DrapeResult dn = measure_drape(*sys, setup);
        out.push_back({s.param, v, (up.metrics.drape_coefficient_percent - dn.metrics.drape_coefficient_percent) / (2 * e),
                       (up.hem.mean_z - dn.hem.mean_z) / (2 * e), s.solve_residual});
    }
    return out;
}

} // namespace drape::cloth
