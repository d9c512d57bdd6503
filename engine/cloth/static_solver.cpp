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

/// A start where two parts of the cloth touch (or one passes through the other: a
/// garment file made that way) has no finite barrier energy to descend from: true,
/// with st saying so.
bool touches_itself(const ClothSystem& s, SolverStatus& st)
{
    if (!s.self_contact_on()) return false;
    const double close = 1e-3 * s.model().self_contact_distance;
    for (const auto& p : s.self_contact_pairs(s.x)) {
        std::array<Eigen::Vector3d, 4> y;
        for (std::size_t k = 0; k < 4; ++k) y[k] = s.x.row(p.v[k]).transpose();
        if (!(pair_squared_distance(p.kind, y) > close * close)) {
            st.outcome = SolverStatus::Outcome::Diverged;
            st.message = "the cloth touches or passes through itself at the start (vertices " + std::to_string(p.v[0]) + ", " +
                         std::to_string(p.v[1]) + ", " + std::to_string(p.v[2]) + ", " + std::to_string(p.v[3]) +
                         "); give it a start without self-intersections, or turn self-collision off";
            return true;
        }
    }
    return false;
}

/// RestOptions::checkpoint, as the loop would end here with opt.residual = checkpoint_residual.
void checkpoint(const ClothSystem& s, const RestOptions& opt, const SolverStatus& st, long f0, Clock::time_point t0)
{
    SolverStatus at = st;
    at.outcome = SolverStatus::Outcome::Converged;
    at.max_speed = 0;
    at.force_evaluations = s.force_evaluations - f0;
    at.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    opt.checkpoint(s.x, at);
}

/// How far h may shrink on the exact Hessian before the projected one: the
/// caller's floor, or near rest kLateShiftPseudoTime (a saddle's negative
/// curvature, not the fold branch's choice; RestOptions::late_shift_residual);
/// 0: none.
double exact_shift_floor(const RestOptions& opt, double residual)
{
    if (opt.shift_before_projection > 0) return opt.shift_before_projection;
    if (opt.shift_before_projection == 0 && opt.late_shift_residual > 0 && residual < opt.late_shift_residual) return kLateShiftPseudoTime;
    return 0;
}

/// What the line search compares against: the energy at the start, the Newton
/// step's slope, its proximal term's M/h^2 norm, and the energy scale for rounding.
struct StepEnergy {
    double e0, slope, mdx, e_scale;
};

/// Backtracking from alpha (halved up to 40 times) until the proximal energy falls
/// enough (Armijo), or, near rest where the predicted decrease is below the energy
/// sum's rounding, the force residual does; trial, alpha and e_trial are the last
/// tried. False: no step was accepted.
bool line_search(ClothSystem& s, const Positions& f, const Eigen::Map<const Positions>& D, const StepEnergy& k, Positions& trial,
                 double& alpha, double& e_trial, SolveProfile& prof, bool profiling)
{
    const double e_round = 1e-12 * (std::abs(k.e0) + k.e_scale);
    for (int ls = 0; ls < 40; ++ls) {
        ProfileScope ls_timer(profiling ? &prof.line_search : nullptr);
        ++prof.line_search_trials;
        trial = s.x + alpha * D;
        e_trial = s.potential_energy(trial);
        const double phi = e_trial + 0.5 * alpha * alpha * k.mdx;
        if (phi <= k.e0 + 1e-4 * alpha * k.slope) return true;
        if (-alpha * k.slope < e_round) {
            Positions ft;
            s.conservative_forces(trial, ft);
            mask_pinned(s, ft);
            if (flat(ft).norm() < flat(f).norm()) return true;
        }
        alpha *= 0.5;
    }
    return false;
}

/// --trace: one line per accepted step, with the worst vertex.
void trace_iteration(ClothSystem& s, const SolverStatus& st, const Positions& f, double h, double alpha, double e0, bool exact)
{
    const auto& mass = s.model().mass;
    int imax = 0;
    f.rowwise().norm().maxCoeff(&imax);
    std::fprintf(stderr, "it %ld res %.3e h %.3g alpha %.3g E %.9g  worst v%d r=%.4f z=%.5f |f|/mg=%.3g %s, contacts %d vertex %zu edge\n",
                 st.steps, st.residual, h, alpha, e0, imax, std::hypot(s.x(imax, 0), s.x(imax, 1)), s.x(imax, 2),
                 f.row(imax).norm() / (mass(imax) * 9.81), exact ? "exact" : "projected", s.vertex_contact_count(s.x),
                 s.edges_in_contact(s.x).size());
}

/// Whether the solve ends before this iteration's step: at rest, out of Newton
/// iterations, or cancelled (st says which). The cancel flag is read every
/// iteration, the progress callback at most five times a second (a terminal or a
/// log needs no more).
bool ends_here(const ClothSystem& s, const RestOptions& opt, SolverStatus& st, long f0, Clock::time_point t0, Clock::time_point& last_report)
{
    if (st.residual < opt.residual) {
        st.outcome = SolverStatus::Outcome::Converged;
        return true;
    }
    if (st.steps >= opt.max_newton) {
        st.outcome = SolverStatus::Outcome::NotConverged;
        st.message = "residual " + std::to_string(st.residual) + " after " + std::to_string(st.steps) + " Newton iterations";
        return true;
    }
    st.force_evaluations = s.force_evaluations - f0;
    const auto now = Clock::now();
    st.wall_seconds = std::chrono::duration<double>(now - t0).count();
    const bool report = st.steps == 0 || now - last_report > std::chrono::milliseconds(200);
    if (report) last_report = now;
    if ((opt.cancel && opt.cancel->load()) || (report && opt.progress && !opt.progress(st))) {
        st.outcome = SolverStatus::Outcome::Cancelled;
        return true;
    }
    return false;
}

/// The assembled Hessian factorised: its pattern analysed on the first iteration
/// or when self-contact coupled new vertices (an analysis of the same pattern is
/// reused across solves), then the numeric factorisation; check llt.info().
Cholmod& factorize(const HessianAssembler& H, std::unique_ptr<Cholmod>& llt_p, int& analysed_revision, bool trace, SolveProfile& prof,
                   bool profiling)
{
    if (!llt_p || H.revision() != analysed_revision) {
        analysed_revision = H.revision();
        bool reused = false;
        {
            ProfileScope timer(profiling ? &prof.analyse : nullptr);
            llt_p = take_analysed(H.matrix(), reused);
        }
        if (trace) trace_factor(H.matrix(), *llt_p, reused);
    }
    Cholmod& llt = *llt_p;
    {
        ProfileScope timer(profiling ? &prof.factorize : nullptr);
        llt.factorize(H.matrix());
    }
    return llt;
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
    std::unique_ptr<Cholmod> llt_p;
    int analysed_revision = -1;
    const auto& mass = s.model().mass;
    const double wn = weight_norm(s);
    double h = opt.dt > 0 ? opt.dt : 0.02;
    const double h_max = 50.0, h_min = 1e-6;
    Positions f, trial;
    s.v.setZero();
    int exact_ok = 1;
    double e_x = std::numeric_limits<double>::quiet_NaN(); // potential energy at s.x, when known
    auto last_report = t0;
    bool checkpointed = false; // RestOptions::checkpoint called
    // Energy scale for rounding: the whole cloth lowered by 1 m [J].
    const double e_scale = s.model().total_mass() * 9.81;
    // Friction against the colliders, lagged: every iteration takes the
    // contacts' normal forces and normals at its start (and anchors new
    // contacts there); within the iteration the friction potential is fixed,
    // so the line search sees one energy.
    StaticFriction friction;
    StaticFriction* const outer_friction = s.static_friction;
    // The system's pointers to this solve's locals are put back however it ends
    // (a return, or a callback - progress, checkpoint - that throws).
    struct Restore {
        ClothSystem& s;
        SolveProfile* profile;
        StaticFriction* friction;
        ~Restore()
        {
            s.profile = profile;
            s.static_friction = friction;
        }
    } restore{s, outer_profile, outer_friction};
    const bool frictional = s.model().friction > 0 && !s.colliders().empty();
    if (frictional) s.static_friction = &friction;
    // A start where two parts of the cloth touch (or one passes through the
    // other: a garment file made that way) has no finite barrier energy to
    // descend from; say so instead of stepping on infinities.
    if (touches_itself(s, st)) return st;
    while (true) {
        if (frictional) {
            s.update_static_friction(friction, s.x);
            e_x = std::numeric_limits<double>::quiet_NaN(); // the potential changed with the lag
        }
        s.conservative_forces(s.x, f);
        ++s.force_evaluations;
        mask_pinned(s, f);
        st.residual = flat(f).norm() / wn;
        if (!std::isfinite(st.residual)) {
            st.outcome = SolverStatus::Outcome::Diverged;
            st.message = "non-finite force at iteration " + std::to_string(st.steps);
            break;
        }
        if (opt.checkpoint && !checkpointed && st.residual < opt.checkpoint_residual) {
            checkpointed = true;
            checkpoint(s, opt, st, f0, t0);
        }
        if (ends_here(s, opt, st, f0, t0, last_report)) break;
        const Eigen::VectorXd md = mass / (h * h);
        // The exact Hessian (compressed springs' negative stiffness, the contact
        // normal's turning) whenever it is positive definite: it halves the
        // iterations against the projected one, which is the fallback for a few
        // iterations after a failed factorisation.
        const bool exact = exact_ok > 0;
        H.assemble(s.x, md, 0.0, exact ? HessianAssembler::Projection::None : HessianAssembler::Projection::All);
        Cholmod& llt = factorize(H, llt_p, analysed_revision, opt.trace, prof, profiling);
        ++st.steps;
        if (llt.info() != Eigen::Success) ++prof.failed_factorizations;
        // How far h may shrink on the exact Hessian before the projected one: the
        // caller's floor, or near rest kLateShiftPseudoTime (a saddle's negative
        // curvature, not the fold branch's choice; RestOptions::late_shift_residual).
        const double shift_floor = exact_shift_floor(opt, st.residual);
        if (llt.info() != Eigen::Success && exact && shift_floor > 0 && h > shift_floor) {
            // A larger proximal shift M / h^2 on the exact Hessian first
            // (RestOptions::shift_before_projection, late_shift_residual).
            h = std::max(0.25 * h, shift_floor);
            continue;
        }
        if (llt.info() != Eigen::Success && exact) {
            exact_ok = -5; // back off from the exact Hessian for a few iterations
            continue;
        }
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
        const Eigen::VectorXd dx = [&] {
            ProfileScope timer(profiling ? &prof.solve : nullptr);
            return Eigen::VectorXd(llt.solve(flat(f)));
        }();
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
        // Self-contact: the longest part of the step along which no two parts of
        // the cloth can pass through each other (the barrier is infinite at touching).
        const double alpha_full = s.self_contact_step_bound(s.x, D);
        double alpha = alpha_full;
        const bool accepted = line_search(s, f, D, {e0, slope, mdx, e_scale}, trial, alpha, e_trial, prof, profiling);
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
        if (opt.trace) trace_iteration(s, st, f, h, alpha, e0, exact);
        // A step the line search took whole (as far as the self-contact filter
        // let it go) lets the pseudo-time grow.
        if (alpha == alpha_full) h = std::min(h * 2.0, h_max);
        else if (alpha < 0.25 * alpha_full) h = std::max(h * 0.5, h_min);
    }
    st.max_speed = 0;
    keep_analysed(std::move(llt_p), H.matrix());
    st.force_evaluations = s.force_evaluations - f0;
    st.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    if (profiling) {
        prof.total = st.wall_seconds;
        prof.print(stderr, "static solver profile (" + std::to_string(n) + " vertices, " + to_string(st.outcome) + ")", st.steps);
    }
    return st;
}


} // namespace

SolverStatus run_static(ClothSystem& s, const RestOptions& opt)
{
    return run_proximal(s, opt);
}

} // namespace drape::cloth::detail
