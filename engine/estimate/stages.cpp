#include "engine/estimate/stages.hpp"

#include "engine/core/error.hpp"
#include "engine/estimate/root.hpp"

#include <algorithm>
#include <exception>

namespace drape::estimate::detail {

namespace {

struct NloptContext {
    Evaluator* ev;
    Start from;
    std::string stage;
    bool cancelled = false;
    std::exception_ptr error; ///< a simulation's error, rethrown after the stage
    nlopt::opt* opt = nullptr;
};

double nlopt_objective(const std::vector<double>& x, std::vector<double>& grad, void* data)
{
    auto* c = static_cast<NloptContext*>(data);
    if (!grad.empty()) std::fill(grad.begin(), grad.end(), 0.0);
    if (c->cancelled || c->error) return HUGE_VAL;
    try {
        return c->ev->objective(Eigen::Map<const Eigen::VectorXd>(x.data(), static_cast<Eigen::Index>(x.size())), c->from, c->stage);
    } catch (const CancelledFit&) {
        c->cancelled = true;
    } catch (...) {
        // NLopt's C++ wrapper turns any exception into a generic "nlopt
        // failure": keep the real one and stop.
        c->error = std::current_exception();
    }
    c->opt->force_stop();
    return HUGE_VAL;
}

} // namespace

bool run_stage(nlopt::algorithm alg, Evaluator& ev, const std::vector<FitVariable>& vars, Eigen::VectorXd& x, int maxeval,
               Start from, const std::string& stage, std::uint64_t seed, const Box& box)
{
    const unsigned n = static_cast<unsigned>(vars.size());
    nlopt::opt opt(alg, n);
    std::vector<double> lo(n), hi(n), step(n);
    for (unsigned i = 0; i < n; ++i) {
        lo[i] = box.empty() ? vars[i].lower : box[i].first;
        hi[i] = box.empty() ? vars[i].upper : box[i].second;
        step[i] = vars[i].log_scale ? 0.3 : 0.1 * (hi[i] - lo[i]);
    }
    opt.set_lower_bounds(lo);
    opt.set_upper_bounds(hi);
    opt.set_maxeval(maxeval);
    if (alg == nlopt::GN_CRS2_LM) {
        opt.set_population(2 * n + 2);
    } else {
        opt.set_initial_step(step);
        std::vector<double> xtol(n);
        for (unsigned i = 0; i < n; ++i) xtol[i] = vars[i].log_scale ? 0.01 : 0.005 * (vars[i].upper - vars[i].lower);
        opt.set_xtol_abs(xtol);
        opt.set_ftol_abs(0.05);
    }
    nlopt::srand(seed);
    NloptContext ctx{&ev, from, stage, false, nullptr, &opt};
    opt.set_min_objective(nlopt_objective, &ctx);
    std::vector<double> xv(x.data(), x.data() + x.size());
    for (unsigned i = 0; i < n; ++i) xv[i] = std::clamp(xv[i], lo[i], hi[i]);
    double f = 0;
    try {
        opt.optimize(xv, f);
    } catch (const nlopt::forced_stop&) {
    } catch (const nlopt::roundoff_limited&) {
    } catch (const std::runtime_error&) {
        // NLopt's generic failure (e.g. a flat objective): keep the best point.
        // A failure of our own objective is in ctx.error and rethrown below.
    }
    if (ctx.error) std::rethrow_exception(ctx.error);
    if (ev.best_x().size() == x.size()) x = ev.best_x();
    return ctx.cancelled;
}

void scan_bending(Evaluator& ev, const std::vector<FitVariable>& vars, const std::vector<int>& bend_vars, int budget,
                  Eigen::VectorXd& x, Box& box)
{
    const double lower = vars[static_cast<std::size_t>(bend_vars[0])].lower, upper = vars[static_cast<std::size_t>(bend_vars[0])].upper;
    int used = 0;
    double best_c = 0, best_err = HUGE_VAL;
    auto dc_error = [&](double c) { // mean simulated - measured D [points]
        for (int i : bend_vars) x[i] = c;
        ev.objective(x, Start::Cold, "scan");
        ++used;
        double err = 0;
        int cnt = 0;
        for (const auto& t : ev.last().terms)
            if (t.kind == "dc") err += t.simulated - t.measured, ++cnt;
        err = cnt ? err / cnt : 0.0;
        if (std::abs(err) < std::abs(best_err)) best_err = err, best_c = c;
        return err;
    };
    double c0 = 0;
    for (int i : bend_vars) c0 += x[i] / static_cast<double>(bend_vars.size());
    c0 = std::clamp(c0, lower, upper);
    const double e0 = dc_error(c0);
    constexpr double tol = 0.5;
    bool bracketed = false;
    double lo = c0, hi = c0, elo = e0, ehi = e0;
    // Step a decade at a time towards the measured D until the sign changes.
    double c = c0, e = e0;
    while (std::abs(e) > tol && used < budget) {
        const double cn = std::clamp(c + (e > 0 ? -1.0 : 1.0), lower, upper);
        if (cn == c) break; // at a bound: the bound is the answer
        const double en = dc_error(cn);
        if ((en > 0) != (e > 0)) {
            bracketed = true;
            if (cn < c) lo = cn, elo = en, hi = c, ehi = e;
            else lo = c, elo = e, hi = cn, ehi = en;
            break;
        }
        c = cn;
        e = en;
    }
    // Regula falsi with the Illinois modification inside the bracket (dc_error
    // keeps the best point).
    if (bracketed && std::abs(best_err) > tol) illinois_root(dc_error, lo, elo, hi, ehi, tol, budget - used);
    for (int i : bend_vars) {
        const auto& v = vars[static_cast<std::size_t>(i)];
        x[i] = best_c;
        box[static_cast<std::size_t>(i)] = {std::max(v.lower, best_c - 0.7), std::min(v.upper, best_c + 0.7)};
    }
}

bool mirror_check(Evaluator& ev, const std::vector<FitVariable>& vars, const std::vector<int>& bend_vars, Eigen::VectorXd& x,
                  int local, Start from, std::uint64_t seed)
{
    if (bend_vars.size() != 2 || ev.best_x().size() != x.size()) return false;
    Eigen::VectorXd xs = ev.best_x();
    std::swap(xs[bend_vars[0]], xs[bend_vars[1]]);
    if (std::abs(xs[bend_vars[0]] - xs[bend_vars[1]]) <= 0.05) return false;
    try {
        const double before = ev.best().chi2;
        const double mirrored = ev.objective(xs, from, "mirror");
        if (mirrored < before) {
            x = xs;
            return run_stage(nlopt::LN_BOBYQA, ev, vars, x, local, from, "local", seed);
        }
    } catch (const CancelledFit&) {
        return true;
    }
    return false;
}

} // namespace drape::estimate::detail
