#include "engine/cloth/solver_detail.hpp"
#include "engine/cloth/sparse_cholesky.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <string>

namespace drape::cloth::detail {

namespace {

using Clock = std::chrono::steady_clock;

void trace_factor(const SpMat& A, Cholmod& llt, bool reused)
{
    std::fprintf(stderr, "static solver: %ld unknowns, %ld Hessian entries, factor %g entries, %g flop per factorisation (ordering %s%s)\n",
                 (long)A.rows(), (long)A.nonZeros(), llt.cholmod().lnz, llt.cholmod().fl, uses_metis(llt) ? "METIS" : "other",
                 reused ? ", analysis reused" : "");
}

/// Static solver: the rest state as a minimum of the potential energy, found by
/// Newton's method regularised with a proximal mass term M/h^2 (a fully damped
/// implicit step of pseudo-time h). h grows while full Newton steps are
/// accepted and shrinks when the line search cuts them, so the method behaves
/// like damped dynamics far from rest (the folds form as they would in a real
/// fall) and like pure Newton near it. The proximal term also removes the
/// neutral modes of a frictionless contact (sliding and spinning on the disc).
SolverStatus run_proximal(ClothSystem& s, const RestOptions& opt)
{
    SolverStatus st;
    const auto t0 = Clock::now();
    SolveProfile prof;
    SolveProfile* const outer_profile = s.profile;
    const bool profiling = opt.trace || std::getenv("DRAPE_PROFILE");
    if (profiling) s.profile = &prof;
    const long f0 = s.force_evaluations;
    const int n = s.vertex_count();
    HessianAssembler H(s);
    std::unique_ptr<HessianAssembler> HE; // exact Hessian for the CG refinement
    std::unique_ptr<Cholmod> llt_p;
    const auto& mass = s.model().mass;
    const double wn = weight_norm(s);
    double h = opt.dt > 0 ? opt.dt : 0.02;
    const double h_max = 50.0, h_min = 1e-6;
    Positions f, trial;
    s.v.setZero();
    int exact_ok = 1;
    int exact_fails = 0;
    const bool shift_policy = opt.shift_exact;
    double e_x = std::numeric_limits<double>::quiet_NaN(); // potential energy at s.x, when known
    auto last_report = t0;
    // Energy scale for rounding: the whole cloth lowered by 1 m [J].
    const double e_scale = s.model().total_mass() * 9.81;
    while (true) {
        s.conservative_forces(s.x, f);
        ++s.force_evaluations;
        mask_pinned(s, f);
        st.residual = flat(f).norm() / wn;
        if (!std::isfinite(st.residual)) {
            st.outcome = SolverStatus::Outcome::Diverged;
            st.message = "non-finite force at iteration " + std::to_string(st.steps);
            break;
        }
        if (st.residual < opt.residual) {
            st.outcome = SolverStatus::Outcome::Converged;
            break;
        }
        if (st.steps >= opt.max_newton) {
            st.outcome = SolverStatus::Outcome::NotConverged;
            st.message = "residual " + std::to_string(st.residual) + " after " + std::to_string(st.steps) + " Newton iterations";
            break;
        }
        st.force_evaluations = s.force_evaluations - f0;
        const auto now = Clock::now();
        st.wall_seconds = std::chrono::duration<double>(now - t0).count();
        // The cancel flag is read every iteration, the progress callback at most
        // five times a second (a terminal or a log needs no more).
        const bool report = st.steps == 0 || now - last_report > std::chrono::milliseconds(200);
        if (report) last_report = now;
        if ((opt.cancel && opt.cancel->load()) || (report && opt.progress && !opt.progress(st))) {
            st.outcome = SolverStatus::Outcome::Cancelled;
            break;
        }
        const Eigen::VectorXd md = mass / (h * h);
        // The exact Hessian (compressed springs' negative stiffness, the contact
        // normal's turning) whenever it is positive definite: it halves the
        // iterations against the projected one, which is the fallback for a few
        // iterations after a failed factorisation.
        static const int pcg_its = [] {
            const char* e = std::getenv("DRAPE_PCG");
            return e ? std::atoi(e) : 0;
        }();
        const bool exact = pcg_its == 0 && exact_ok > 0;
        static const HessianAssembler::Projection exact_form = [] {
            const char* e = std::getenv("DRAPE_EXACT_FORM");
            return e && std::string(e) == "springs" ? HessianAssembler::Projection::Springs : HessianAssembler::Projection::None;
        }();
        H.assemble(s.x, md, 0.0, exact ? exact_form : HessianAssembler::Projection::All);
        if (!llt_p) {
            bool reused = false;
            {
                ProfileScope timer(profiling ? &prof.analyse : nullptr);
                llt_p = take_analysed(H.matrix(), reused);
            }
            if (opt.trace) trace_factor(H.matrix(), *llt_p, reused);
        }
        Cholmod& llt = *llt_p;
        {
            ProfileScope timer(profiling ? &prof.factorize : nullptr);
            llt.factorize(H.matrix());
        }
        ++st.steps;
        if (llt.info() != Eigen::Success) ++prof.failed_factorizations;
        if (llt.info() != Eigen::Success && exact) {
            if (shift_policy && ++exact_fails <= 3) {
                // Indefinite: the exact Hessian with a 16x stronger proximal shift
                // (Levenberg-Marquardt in the mass metric) keeps the curvature
                // information that the projected form throws away.
                h = std::max(h * 0.25, h_min);
                continue;
            }
            exact_fails = 0;
            exact_ok = -5; // back off from the exact Hessian for a few iterations
            continue;
        }
        if (exact) exact_fails = 0;
        if (exact_ok <= 0) ++exact_ok;
        if (llt.info() != Eigen::Success) {
            h *= 0.25;
            if (h < h_min) {
                st.outcome = SolverStatus::Outcome::Diverged;
                st.message = "Hessian not positive definite even with strong regularisation";
                break;
            }
            continue;
        }
        Eigen::VectorXd dx = [&] {
            ProfileScope timer(profiling ? &prof.solve : nullptr);
            return Eigen::VectorXd(llt.solve(flat(f)));
        }();
        if (pcg_its > 0) {
            // Truncated conjugate gradients on the exact Hessian (plus the same
            // proximal shift), preconditioned by the projected one just factorised
            // (Steihaug): the projected Newton step is the first iterate; CG refines
            // it towards the exact Newton step while the curvature stays positive,
            // and stops at the first direction of negative curvature.
            if (!HE) HE = std::make_unique<HessianAssembler>(s);
            HE->assemble(s.x, md, 0.0, HessianAssembler::Projection::None);
            const auto A = HE->matrix().selfadjointView<Eigen::Upper>();
            const Eigen::VectorXd b = flat(f);
            Eigen::VectorXd p = Eigen::VectorXd::Zero(b.size()), r = b, z = dx, d = z, Ad;
            double rz = r.dot(z);
            const double bn = b.norm();
            int k = 0;
            for (; k < pcg_its; ++k) {
                Ad = A * d;
                const double dAd = d.dot(Ad);
                if (!(dAd > 0)) break; // negative curvature
                const double a = rz / dAd;
                p += a * d;
                r -= a * Ad;
                if (r.norm() <= 1e-3 * bn) {
                    ++k;
                    break;
                }
                z = llt.solve(r);
                const double rz_new = r.dot(z);
                d = z + (rz_new / rz) * d;
                rz = rz_new;
            }
            prof.cg_iterations += k;
            if (k > 0) dx = p;
        }
        ++st.newton_iterations;
        const Eigen::Map<const Positions> D(dx.data(), n, 3);
        // The energy at s.x is known from the line search that accepted it.
        if (std::isnan(e_x)) e_x = s.potential_energy(s.x);
        const double e0 = e_x;
        double e_trial = e0;
        const double slope = -flat(f).dot(dx);
        const double mdx = [&] {
            double q = 0;
            for (int i = 0; i < n; ++i) q += md(i) * D.row(i).squaredNorm();
            return q;
        }();
        double alpha = 1;
        bool accepted = false;
        // Near rest the predicted energy decrease falls below the rounding error
        // of the energy sum; there the step is judged by the force residual instead.
        const double e_round = 1e-12 * (std::abs(e0) + e_scale);
        for (int ls = 0; ls < 40; ++ls) {
            ProfileScope ls_timer(profiling ? &prof.line_search : nullptr);
            ++prof.line_search_trials;
            trial = s.x + alpha * D;
            e_trial = s.potential_energy(trial);
            const double phi = e_trial + 0.5 * alpha * alpha * mdx;
            if (phi <= e0 + 1e-4 * alpha * slope) {
                accepted = true;
                break;
            }
            if (-alpha * slope < e_round) {
                Positions ft;
                s.conservative_forces(trial, ft);
                mask_pinned(s, ft);
                if (flat(ft).norm() < flat(f).norm()) {
                    accepted = true;
                    break;
                }
            }
            alpha *= 0.5;
        }
        if (!accepted) {
            h *= 0.25;
            if (h < h_min) {
                st.outcome = SolverStatus::Outcome::NotConverged;
                st.message = "line search failed at residual " + std::to_string(st.residual);
                break;
            }
            continue;
        }
        s.x = trial;
        e_x = e_trial;
        if (opt.trace)
        {
            int imax = 0;
            f.rowwise().norm().maxCoeff(&imax);
            std::fprintf(stderr, "it %ld res %.3e h %.3g alpha %.3g E %.9g  worst v%d r=%.4f z=%.5f |f|/mg=%.3g %s, contacts %d vertex %zu edge\n",
                         st.steps, st.residual, h, alpha, e0, imax, std::hypot(s.x(imax, 0), s.x(imax, 1)), s.x(imax, 2),
                         f.row(imax).norm() / (mass(imax) * 9.81), exact ? "exact" : "projected", s.vertex_contact_count(s.x),
                         s.edges_in_contact(s.x).size());
        }
        if (alpha == 1.0) h = std::min(h * 2.0, h_max);
        else if (alpha < 0.25) h = std::max(h * 0.5, h_min);
    }
    st.max_speed = 0;
    if (s.model().friction > 0)
        st.message += std::string(st.message.empty() ? "" : "; ") +
                      "the static solver treats contact as frictionless (a rest state with friction depends on the path: use "
                      "the implicit or an explicit integrator)";
    keep_analysed(std::move(llt_p), H.matrix());
    st.force_evaluations = s.force_evaluations - f0;
    st.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (profiling) {
        prof.total = st.wall_seconds;
        prof.print(stderr, "static solver profile (" + std::to_string(n) + " vertices, " + to_string(st.outcome) + ")", st.steps);
    }
    s.profile = outer_profile;
    return st;
}


/// Static solver, trust-region form: Newton on the exact Hessian with a
/// Levenberg-Marquardt shift in the mass metric, (H + mu M) p = f, mu adapted
/// by how well the quadratic model predicted the energy drop (rho). Where H is
/// indefinite (the sheet is buckling, or sits near a saddle) mu grows until
/// H + mu M is positive definite, and the step is longest along the negative
/// curvature: the solver leaves a saddle instead of creeping along it, which
/// the projected Hessian (negative terms dropped) does at a linear rate. Near a
/// minimum mu shrinks to nothing and the steps are Newton's (quadratic rate).
/// A large mu is a fully damped implicit step of pseudo-time 1 / sqrt(mu), so
/// from a flat start the sheet falls as damped dynamics would.
SolverStatus run_trust_region(ClothSystem& s, const RestOptions& opt)
{
    SolverStatus st;
    const auto t0 = Clock::now();
    SolveProfile prof;
    SolveProfile* const outer_profile = s.profile;
    const bool profiling = opt.trace || std::getenv("DRAPE_PROFILE");
    if (profiling) s.profile = &prof;
    const long f0 = s.force_evaluations;
    const int n = s.vertex_count();
    HessianAssembler H(s);
    std::unique_ptr<Cholmod> llt_p;
    const Eigen::VectorXd& mass = s.model().mass;
    const double wn = weight_norm(s);
    const double h0 = opt.dt > 0 ? opt.dt : 0.02;
    double mu = 1.0 / (h0 * h0);          // [1/s^2]
    const double mu_min = 1e-8, mu_max = 1e14;
    Positions f, trial, ft;
    s.v.setZero();
    double e_x = s.potential_energy(s.x);
    const double e_scale = s.model().total_mass() * 9.81; // the cloth lowered by 1 m [J]
    auto last_report = t0;
    long rejected = 0;
    s.conservative_forces(s.x, f);
    ++s.force_evaluations;
    mask_pinned(s, f);
    while (true) {
        st.residual = flat(f).norm() / wn;
        if (!std::isfinite(st.residual) || !std::isfinite(e_x)) {
            st.outcome = SolverStatus::Outcome::Diverged;
            st.message = "non-finite force or energy at iteration " + std::to_string(st.steps);
            break;
        }
        if (st.residual < opt.residual) {
            st.outcome = SolverStatus::Outcome::Converged;
            break;
        }
        if (st.steps >= opt.max_newton) {
            st.outcome = SolverStatus::Outcome::NotConverged;
            st.message = "residual " + std::to_string(st.residual) + " after " + std::to_string(st.steps) + " Newton iterations";
            break;
        }
        st.force_evaluations = s.force_evaluations - f0;
        const auto now = Clock::now();
        st.wall_seconds = std::chrono::duration<double>(now - t0).count();
        const bool report = st.steps == 0 || now - last_report > std::chrono::milliseconds(200);
        if (report) last_report = now;
        if ((opt.cancel && opt.cancel->load()) || (report && opt.progress && !opt.progress(st))) {
            st.outcome = SolverStatus::Outcome::Cancelled;
            break;
        }
        H.assemble(s.x, mu * mass, 0.0, false);
        if (!llt_p) {
            bool reused = false;
            {
                ProfileScope timer(profiling ? &prof.analyse : nullptr);
                llt_p = take_analysed(H.matrix(), reused);
            }
            if (opt.trace) trace_factor(H.matrix(), *llt_p, reused);
        }
        Cholmod& llt = *llt_p;
        {
            ProfileScope timer(profiling ? &prof.factorize : nullptr);
            llt.factorize(H.matrix());
        }
        ++st.steps;
        if (llt.info() != Eigen::Success) {
            ++prof.failed_factorizations;
            // Not positive definite: a stronger shift (at least one a soft mode
            // notices: the bending scale of a vertex is ~1e2..1e4 1/s^2).
            mu = std::max(mu * 8.0, 1.0);
            if (mu > mu_max) {
                st.outcome = SolverStatus::Outcome::Diverged;
                st.message = "Hessian not positive definite even with a shift of " + std::to_string(mu) + " 1/s^2";
                break;
            }
            continue;
        }
        const Eigen::VectorXd p = [&] {
            ProfileScope timer(profiling ? &prof.solve : nullptr);
            return Eigen::VectorXd(llt.solve(flat(f)));
        }();
        ++st.newton_iterations;
        const Eigen::Map<const Positions> P(p.data(), n, 3);
        double pmp = 0;
        for (int i = 0; i < n; ++i) pmp += mass(i) * P.row(i).squaredNorm();
        const double fp = flat(f).dot(p);
        // Drop of the quadratic model -f.p + p.H.p/2 (H unshifted) along p.
        const double predicted = 0.5 * (fp + mu * pmp);
        const double e_round = 1e-12 * (std::abs(e_x) + e_scale);
        double alpha = 1.0, e_trial = e_x;
        bool accepted = false;
        double rho = 0;
        for (int ls = 0; ls < 3; ++ls) {
            ProfileScope ls_timer(profiling ? &prof.line_search : nullptr);
            ++prof.line_search_trials;
            trial = s.x + alpha * P;
            e_trial = s.potential_energy(trial);
            const double actual = e_x - e_trial;
            const double pred = alpha * fp - 0.5 * alpha * alpha * (fp - mu * pmp); // model drop at alpha p
            rho = pred > 0 ? actual / pred : -1;
            if (pred < e_round || std::abs(actual) < e_round) {
                // Below the energy's rounding: judge by the force residual.
                s.conservative_forces(trial, ft);
                mask_pinned(s, ft);
                if (flat(ft).norm() < flat(f).norm()) {
                    accepted = true;
                    rho = 1;
                }
                break;
            }
            if (rho > 0.1) {
                accepted = true;
                break;
            }
            alpha *= 0.25; // a shorter step before a new factorisation
        }
        (void)predicted;
        if (!accepted) {
            ++rejected;
            mu = std::max(mu * 8.0, 1.0);
            if (mu > mu_max) {
                st.outcome = SolverStatus::Outcome::NotConverged;
                st.message = "no descent step at residual " + std::to_string(st.residual);
                break;
            }
            continue;
        }
        s.x = trial;
        e_x = e_trial;
        s.conservative_forces(s.x, f);
        ++s.force_evaluations;
        mask_pinned(s, f);
        if (opt.trace) {
            int imax = 0;
            f.rowwise().norm().maxCoeff(&imax);
            std::fprintf(stderr, "it %ld res %.3e mu %.3g alpha %.3g rho %.3f E %.12g  worst v%d r=%.4f z=%.5f\n", st.steps,
                         flat(f).norm() / wn, mu, alpha, rho, e_x, imax, std::hypot(s.x(imax, 0), s.x(imax, 1)), s.x(imax, 2));
        }
        if (alpha == 1.0 && rho > 0.75) mu = mu / 4.0 < mu_min ? 0.0 : mu / 4.0;
        else if (alpha < 1.0 || rho < 0.25) mu = std::max(mu * 2.0, 1.0);
    }
    st.max_speed = 0;
    if (s.model().friction > 0)
        st.message += std::string(st.message.empty() ? "" : "; ") +
                      "the static solver treats contact as frictionless (a rest state with friction depends on the path: use "
                      "the implicit or an explicit integrator)";
    keep_analysed(std::move(llt_p), H.matrix());
    st.force_evaluations = s.force_evaluations - f0;
    st.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (profiling) {
        prof.total = st.wall_seconds;
        prof.print(stderr, "static solver profile (" + std::to_string(n) + " vertices, " + to_string(st.outcome) + ", " +
                               std::to_string(rejected) + " rejected steps)", st.steps);
    }
    s.profile = outer_profile;
    return st;
}

} // namespace

SolverStatus run_static(ClothSystem& s, const RestOptions& opt)
{
    static const bool tr = [] {
        const char* e = std::getenv("DRAPE_STATIC");
        return e && std::string(e) == "tr";
    }();
    return tr ? run_trust_region(s, opt) : run_proximal(s, opt);
}

} // namespace drape::cloth::detail
