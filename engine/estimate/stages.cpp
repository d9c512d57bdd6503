#include "engine/estimate/detail/stages.hpp"

#include "engine/core/error.hpp"
#include "engine/estimate/root.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <exception>

namespace drape::estimate::detail {

namespace {

struct NloptContext {
    Evaluator* ev;
    Start from;
    Stage stage;
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
               Start from, Stage stage, std::uint64_t seed, const Box& box)
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
                  Eigen::VectorXd& x, Box& box, bool newton)
{
    const double lower = vars[static_cast<std::size_t>(bend_vars[0])].lower, upper = vars[static_cast<std::size_t>(bend_vars[0])].upper;
    int used = 0;
    double best_c = 0, best_err = HUGE_VAL;
    auto dc_error = [&](double c) { // mean simulated - measured D [points]
        for (int i : bend_vars) x[i] = c;
        // The fit's start is often the scan's first point: its cold drapes are the last evaluation.
        if (!(used == 0 && ev.last_x().size() == x.size() && ev.last_x() == x)) ev.objective(x, Start::Cold, Stage::Scan);
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
    if (newton) {
        // Safeguarded Newton on the exact slope dD/dc of the drape just made (its
        // rest-state sensitivities): a step at most a decade long, inside the
        // bracket once the sign has changed (else the bracket's midpoint).
        double c = c0, e = e0;
        double blo = lower, bhi = upper; // bracket: D - Dm < 0 at blo, > 0 at bhi (when seen)
        bool seen_lo = false, seen_hi = false;
        while (std::abs(e) > tol && used < budget) {
            if (e > 0) bhi = c, seen_hi = true;
            else blo = c, seen_lo = true;
            const Eigen::MatrixXd J = ev.jacobian(x, ev.last(), false);
            double slope = 0;
            int cnt = 0;
            for (std::size_t k = 0; k < ev.last().terms.size(); ++k) {
                const auto& t = ev.last().terms[k];
                if (t.kind != "dc") continue;
                for (int i : bend_vars) slope += J(static_cast<Eigen::Index>(k), i) * t.sigma;
                ++cnt;
            }
            slope = cnt ? slope / cnt : 0.0;
            double cn;
            if (slope > 1e-3) cn = c - std::clamp(e / slope, -1.0, 1.0);
            else cn = c + (e > 0 ? -1.0 : 1.0); // no usable slope: a decade towards the measured D
            if (seen_lo && seen_hi && !(cn > blo && cn < bhi)) cn = 0.5 * (blo + bhi); // outside the bracket: bisect
            cn = std::clamp(cn, lower, upper);
            if (std::abs(cn - c) < 0.005) break; // at a bound, or converged below the coordinate's resolution
            c = cn;
            e = dc_error(c);
        }
        for (int i : bend_vars) {
            const auto& v = vars[static_cast<std::size_t>(i)];
            x[i] = best_c;
            box[static_cast<std::size_t>(i)] = {std::max(v.lower, best_c - 0.7), std::min(v.upper, best_c + 0.7)};
        }
        return;
    }
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

bool levenberg_marquardt(Evaluator& ev, const std::vector<FitVariable>& vars, Eigen::VectorXd& x, const Box& box, int budget,
                         Stage stage, Start from)
{
    const int n = static_cast<int>(vars.size());
    std::vector<double> lo(static_cast<std::size_t>(n)), hi(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
        lo[static_cast<std::size_t>(i)] = box.empty() ? vars[static_cast<std::size_t>(i)].lower : box[static_cast<std::size_t>(i)].first;
        hi[static_cast<std::size_t>(i)] = box.empty() ? vars[static_cast<std::size_t>(i)].upper : box[static_cast<std::size_t>(i)].second;
    }
    // A coordinate the box pins (lower = upper: a held shear) is out of the step:
    // its row and column out of the normal equations and of the trust radius, so
    // that the others' step is the least-squares step with it held (solved with it,
    // the coordinate the data sees least would propose the longest move, shrink
    // everyone's step to the radius and then be clamped back).
    std::vector<char> pinned(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) pinned[static_cast<std::size_t>(i)] = hi[static_cast<std::size_t>(i)] <= lo[static_cast<std::size_t>(i)] ? 1 : 0;
    // Every evaluation counts, the Jacobian's fallback re-solves too.
    const int at_entry = ev.evaluations();
    auto used_now = [&] { return ev.evaluations() - at_entry; };
    try {
        if (ev.best_x().size() != x.size()) ev.objective(x, Start::Cold, stage);
        x = ev.best_x();
        double lambda = 0.1;
        // Trust radius as a fraction of the largest step (half a decade on log
        // scales, a tenth of the range otherwise): halved on every rejected step,
        // so a coordinate the data hardly sees (a small diagonal of J^T J, whose
        // Marquardt damping stays weak) cannot keep proposing the same far step.
        double radius = 1.0;
        while (used_now() < budget) {
            const Evaluation cur = ev.best();
            const Eigen::MatrixXd J = ev.jacobian(x, cur);
            Eigen::VectorXd r = Eigen::VectorXd::Zero(J.rows());
            for (Eigen::Index k = 0; k < J.rows(); ++k)
                if (cur.terms[static_cast<std::size_t>(k)].fitted) r[k] = cur.terms[static_cast<std::size_t>(k)].whitened();
            Eigen::MatrixXd A = J.transpose() * J;
            Eigen::VectorXd g = J.transpose() * r;
            for (int i = 0; i < n; ++i)
                if (pinned[static_cast<std::size_t>(i)]) {
                    A.row(i).setZero();
                    A.col(i).setZero();
                    g[i] = 0;
                }
            const double amax = std::max(A.diagonal().maxCoeff(), 1e-300);
            if (!(g.allFinite() && A.allFinite()) || amax <= 1e-300) return false; // the data does not see any coordinate
            bool accepted = false;
            double gain = 0;
            Eigen::VectorXd step;
            while (used_now() < budget) {
                Eigen::MatrixXd M = A;
                for (int i = 0; i < n; ++i) M(i, i) += pinned[static_cast<std::size_t>(i)] ? 1.0 : lambda * std::max(A(i, i), 1e-9 * amax) + 1e-12 * amax;
                Eigen::VectorXd d = -M.ldlt().solve(g);
                // Half a decade at most per step on log scales (the linearisation of
                // a rest state does not reach further), a tenth of the range otherwise.
                double scale = 1;
                for (int i = 0; i < n; ++i) {
                    if (pinned[static_cast<std::size_t>(i)]) continue;
                    const auto& v = vars[static_cast<std::size_t>(i)];
                    const double cap = radius * (v.log_scale ? 0.5 : 0.1 * (v.upper - v.lower));
                    if (std::abs(d[i]) > cap) scale = std::min(scale, cap / std::abs(d[i]));
                }
                d *= scale;
                Eigen::VectorXd xn = x + d;
                for (int i = 0; i < n; ++i) xn[i] = std::clamp(xn[i], lo[static_cast<std::size_t>(i)], hi[static_cast<std::size_t>(i)]);
                step = xn - x;
                bool moves = false;
                for (int i = 0; i < n; ++i) {
                    const auto& v = vars[static_cast<std::size_t>(i)];
                    const double xtol = v.log_scale ? 0.003 : 0.002 * (v.upper - v.lower);
                    moves = moves || std::abs(step[i]) > xtol;
                }
                if (!moves) return false; // converged: the step is below the coordinates' resolution
                const double predicted = -(2 * g.dot(step) + step.dot(A * step));
                const double before = cur.chi2;
                ev.objective(xn, from, stage);
                // Taken when it became the best point: a lower chi2 from drapes that did
                // not come to rest is no drape of the model (Evaluator::objective).
                const double after = ev.best().chi2;
                if (after < before) {
                    gain = before - after;
                    const double rho = predicted > 0 ? gain / predicted : 0.0;
                    lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2 * rho - 1, 3));
                    if (rho > 0.75) radius = std::min(1.0, 2 * radius);
                    x = ev.best_x();
                    accepted = true;
                    break;
                }
                lambda = std::max(lambda, 1e-4) * 4;
                radius *= 0.5;
                if (lambda > 1e6) return false; // no descent along any damped step: a minimum at this resolution
            }
            // A gain below 0.2 in chi2 moves the parameters by a small fraction of
            // their 1-sigma (a change of 1 in chi2): within the drape-to-drape noise.
            // A fit worse than its noise model (chi2 / dof > 1, as before the spread
            // is calibrated) has its 1-sigma at a change of chi2 / dof (the intervals
            // scale the same way), so the threshold scales with it - taken after the
            // step, and only with at least two terms per coordinate to spare (a fit
            // of a few terms, e.g. D alone, drives chi2 towards 0 as before).
            int fitted_terms = 0;
            for (const auto& t : cur.terms) fitted_terms += t.fitted ? 1 : 0;
            const int dof = fitted_terms - n;
            const double per_dof = dof >= 2 * n ? (cur.chi2 - gain) / dof : 1.0;
            if (!accepted || gain < 0.2 * std::max(1.0, per_dof)) return false;
        }
    } catch (const CancelledFit&) {
        if (ev.best_x().size() == x.size()) x = ev.best_x();
        return true;
    }
    return false;
}

bool mirror_check(Evaluator& ev, const std::vector<FitVariable>& vars, const std::vector<int>& bend_vars, Eigen::VectorXd& x,
                  int local, Start from, std::uint64_t seed, bool lm)
{
    if (bend_vars.size() != 2 || ev.best_x().size() != x.size()) return false;
    Eigen::VectorXd xs = ev.best_x();
    std::swap(xs[bend_vars[0]], xs[bend_vars[1]]);
    if (std::abs(xs[bend_vars[0]] - xs[bend_vars[1]]) <= 0.05) return false;
    try {
        const double before = ev.best().chi2;
        ev.objective(xs, from, Stage::Mirror);
        if (ev.best().chi2 < before) { // the mirrored point became the best (at rest)
            x = xs;
            if (lm) return levenberg_marquardt(ev, vars, x, {}, local, Stage::Local, from);
            return run_stage(nlopt::LN_BOBYQA, ev, vars, x, local, from, Stage::Local, seed);
        }
    } catch (const CancelledFit&) {
        return true;
    }
    return false;
}

Eigen::VectorXd profile_direction(const Eigen::MatrixXd& J, const std::vector<char>& rows, const std::vector<int>& bend, double& curvature)
{
    const Eigen::Index n = J.cols();
    std::vector<int> other;
    for (int i = 0; i < static_cast<int>(n); ++i)
        if (std::find(bend.begin(), bend.end(), i) == bend.end()) other.push_back(i);
    std::vector<Eigen::Index> use;
    for (Eigen::Index k = 0; k < J.rows(); ++k)
        if (static_cast<std::size_t>(k) < rows.size() && rows[static_cast<std::size_t>(k)]) use.push_back(k);
    Eigen::VectorXd dir = Eigen::VectorXd::Zero(n);
    for (int i : bend) dir[i] = 1;
    if (!other.empty() && !use.empty()) {
        Eigen::MatrixXd Jo(static_cast<Eigen::Index>(use.size()), static_cast<Eigen::Index>(other.size()));
        Eigen::VectorXd jb = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(use.size()));
        for (std::size_t k = 0; k < use.size(); ++k) {
            for (std::size_t j = 0; j < other.size(); ++j) Jo(static_cast<Eigen::Index>(k), static_cast<Eigen::Index>(j)) = J(use[k], other[j]);
            for (int i : bend) jb[static_cast<Eigen::Index>(k)] += J(use[k], i);
        }
        // Least squares with column pivoting: a coordinate the rows do not see gets 0.
        const Eigen::VectorXd d = Jo.colPivHouseholderQr().solve(-jb);
        for (std::size_t j = 0; j < other.size(); ++j)
            dir[other[j]] = std::isfinite(d[static_cast<Eigen::Index>(j)]) ? d[static_cast<Eigen::Index>(j)] : 0.0;
    }
    curvature = 0;
    const Eigen::VectorXd jd = J * dir;
    for (Eigen::Index k : use) curvature += jd[k] * jd[k];
    return dir;
}

} // namespace drape::estimate::detail
