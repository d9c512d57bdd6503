// The shear hold (ShearHold::Auto, docs/decisions/0024-shear-hold.md): a shear the
// data leave open-ended held at the typical value and the rest refitted.
#include "engine/estimate/detail/pipeline.hpp"
#include "engine/estimate/detail/stages.hpp"
#include "engine/estimate/detail/uncertainty.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drape::estimate::detail {

using cloth::Param;

void mark_held_shear(FitResult& out)
{
    if (!out.shear_hold.held) return;
    for (auto& e : out.estimates)
        if (e.id == Param::Shear) {
            char buf[300];
            std::snprintf(buf, sizeof buf, "held at the typical value %.4g N/m: the data do not constrain it (95 %% when fitted: %.4g..%.4g N/m%s)",
                          out.shear_hold.held_N_m, out.shear_hold.lower95_N_m, out.shear_hold.upper95_N_m,
                          out.shear_hold.at_bound ? ", at a fit bound" : "");
            e.role = "held";
            e.constrained = false;
            e.note = buf;
        }
}

bool hold_unseen_shear(Evaluator& ev, const std::vector<FitVariable>& vars, const FitOptions& options, int measurement_params, int budget,
                       Start from, FitResult::ShearHeld& h)
{
    h = {};
    const int n = static_cast<int>(vars.size());
    const int is = sole_variable(vars, Param::Shear);
    if (options.shear != ShearHold::Auto || is < 0 || ev.best_x().size() != n || !ev.best().at_rest()) return false;
    const FitVariable& v = vars[static_cast<std::size_t>(is)];
    const Eigen::VectorXd x = ev.best_x();
    const Evaluation fitted = ev.best();
    char buf[500];
    try {
        FitResult scratch; // sigmas_from_jacobian's chi2 / dof scaling and its outputs
        scratch.chi2 = fitted.chi2;
        scratch.dof = fit_dof(fitted.terms, n + measurement_params);
        scratch.correlation = Eigen::MatrixXd::Zero(n, n);
        const Eigen::MatrixXd J = ev.jacobian(x, fitted);
        ev.report(Stage::Shear);
        const double half = 1.96 * sigmas_from_jacobian(J, scratch)[static_cast<std::size_t>(is)];
        h.assessed = true;
        h.fitted_N_m = v.to_value(x[is]);
        h.fitted_chi2 = fitted.chi2;
        h.lower95_N_m = v.to_value(std::isfinite(half) ? std::max(x[is] - half, v.lower) : v.lower);
        h.upper95_N_m = v.to_value(std::isfinite(half) ? std::min(x[is] + half, v.upper) : v.upper);
        // Held where the data leave the shear open-ended: its 95 % interval runs into a
        // fit bound (the box, not the data, ends it on that side) or the search stopped
        // at a bound. An interval inside the box, however wide, says something the
        // typical value would throw away (tst_est_fit_slow's synthetic fabric, shear 20
        // N/m: fitted 37.9 N/m, 7.6..190; held at 56.2 its 240/180 mm prediction
        // moved 2.0 -> 3.2 points off).
        h.at_bound = at_fit_bound(v, x[is]);
        h.constrained = !interval_reaches_bound(v, x[is], half) && !h.at_bound;
        if (h.constrained) {
            std::snprintf(buf, sizeof buf, "shear %.4g N/m (95 %%: %.4g..%.4g with the search's sigmas) is bounded by the data on both sides: fitted",
                          h.fitted_N_m, h.lower95_N_m, h.upper95_N_m);
            h.reason = buf;
            return false;
        }
        const double target = std::clamp(v.to_coord(options.typical_shear_N_m), v.lower, v.upper);
        h.tried = true;
        h.held_N_m = v.to_value(target);
        Eigen::VectorXd xh = x;
        xh[is] = target;
        const Evaluation eh = ev.evaluate(xh, Start::Best);
        ev.report(Stage::Shear);
        if (!eh.at_rest()) {
            std::snprintf(buf, sizeof buf,
                          "shear %.4g N/m (95 %%: %.4g..%.4g) is not constrained by the data, but the drapes at the typical %.4g N/m did not "
                          "come to rest: fitted value kept",
                          h.fitted_N_m, h.lower95_N_m, h.upper95_N_m, h.held_N_m);
            h.reason = buf;
            return false;
        }
        ev.set_best(eh, xh);
        Box box;
        for (const auto& w : vars) box.push_back({w.lower, w.upper});
        box[static_cast<std::size_t>(is)] = {target, target};
        const bool cancelled = levenberg_marquardt(ev, vars, xh, box, budget, Stage::Shear, from);
        h.held_chi2 = ev.best().chi2;
        h.delta_chi2 = (h.held_chi2 - h.fitted_chi2) / std::max(1.0, fitted.chi2 / scratch.dof);
        if (cancelled) {
            ev.set_best(fitted, x);
            h.reason = "shear not constrained by the data; its held refit was cancelled: fitted value kept";
            return true;
        }
        h.held = h.delta_chi2 < kTieChi2;
        if (!h.held) ev.set_best(fitted, x);
        std::snprintf(buf, sizeof buf,
                      "shear %.4g N/m (95 %%: %.4g..%.4g%s) is not constrained by the data; held at the typical value %.4g N/m "
                      "and the rest refitted: chi2 %.1f against %.1f fitted (scaled delta %.2f %s %.0f): %s",
                      h.fitted_N_m, h.lower95_N_m, h.upper95_N_m, h.at_bound ? ", at a fit bound" : "", h.held_N_m, h.held_chi2, h.fitted_chi2,
                      h.delta_chi2, h.held ? "<" : ">=",
                      kTieChi2, h.held ? "held" : "the data need the fitted value, kept");
        h.reason = buf;
        return false;
    } catch (const CancelledFit&) {
        ev.set_best(fitted, x);
        h.held = false;
        h.reason = "shear hold cancelled: fitted value kept";
        return true;
    }
}

} // namespace drape::estimate::detail
