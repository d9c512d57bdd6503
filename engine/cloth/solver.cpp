#include "engine/cloth/solver.hpp"

#include "engine/core/error.hpp"

#include <Eigen/CholmodSupport>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <algorithm>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

// OpenMP's runtime, when CHOLMOD brought it into the process (weak: null otherwise).
extern "C" void omp_set_max_active_levels(int) __attribute__((weak));

namespace drape::cloth {

using SpMat = Eigen::SparseMatrix<double>;
using Cholmod = Eigen::CholmodDecomposition<SpMat, Eigen::Upper>;

namespace {

/// CHOLMOD settings for the cloth Hessians, before analyzePattern.
///
/// Threads: Debian's CHOLMOD 3.0 (SuiteSparse 5.12) runs the copy loops of its
/// supernodal factorisation in OpenMP regions with a compiled-in
/// num_threads(4) (CHOLMOD_OMP_NUM_THREADS), whatever OMP_NUM_THREADS says.
/// On this 2-core machine that made every factorisation wait on futexes: 167 ms
/// instead of 59 ms at 23,004 unknowns (41 s of system time in a 113 s drape).
/// The numerical work is BLAS, which keeps its own threads; the regions are
/// made inactive process-wide (the project has no other OpenMP code) unless the
/// user chose through OMP_MAX_ACTIVE_LEVELS or OMP_THREAD_LIMIT.
///
/// Ordering: METIS nested dissection instead of CHOLMOD's default AMD (METIS is
/// tried by default only when AMD's fill looks poor, and it did not here): on the
/// 100 x 100 disc 1.0 Gflop and 3.7 M factor entries instead of 1.7 Gflop and
/// 4.4 M, factorisation 43 ms instead of 59 ms; the analysis (once per mesh) costs
/// 50 ms instead of 15 ms.
void configure_cholmod(Cholmod& llt)
{
    static std::once_flag once;
    std::call_once(once, [] {
        if (omp_set_max_active_levels && !std::getenv("OMP_MAX_ACTIVE_LEVELS") && !std::getenv("OMP_THREAD_LIMIT"))
            omp_set_max_active_levels(0);
    });
    auto& c = llt.cholmod();
    c.print = 0; // numerical outcomes are reported through the status, not stderr
    llt.setMode(Eigen::CholmodSupernodalLLt);
    const char* ord = std::getenv("DRAPE_CHOLMOD_ORDERING");
    if (!(ord && std::string(ord) == "default")) {
        c.nmethods = 1;
        c.method[0].ordering = CHOLMOD_METIS;
        c.postorder = 1;
    }
}

} // namespace

Integrator parse_integrator(const std::string& name)
{
    if (name == "rk4") return Integrator::RK4;
    if (name == "euler") return Integrator::ExplicitEuler;
    if (name == "symplectic" || name == "semi-implicit") return Integrator::SemiImplicitEuler;
    if (name == "midpoint") return Integrator::Midpoint;
    if (name == "implicit") return Integrator::ImplicitEuler;
    if (name == "static") return Integrator::Static;
    throw ParameterError("integrator: '" + name + "' is not one of rk4, euler, symplectic, midpoint, implicit, static");
}

std::string to_string(Integrator i)
{
    switch (i) {
    case Integrator::RK4: return "rk4";
    case Integrator::ExplicitEuler: return "euler";
    case Integrator::SemiImplicitEuler: return "symplectic";
    case Integrator::Midpoint: return "midpoint";
    case Integrator::ImplicitEuler: return "implicit";
    case Integrator::Static: return "static";
    }
    return "?";
}

std::string to_string(SolverStatus::Outcome o)
{
    switch (o) {
    case SolverStatus::Outcome::Running: return "running";
    case SolverStatus::Outcome::Converged: return "converged";
    case SolverStatus::Outcome::NotConverged: return "not converged";
    case SolverStatus::Outcome::Diverged: return "diverged";
    case SolverStatus::Outcome::Cancelled: return "cancelled";
    }
    return "?";
}

namespace {

Eigen::Map<Eigen::VectorXd> flat(Positions& P) { return {P.data(), P.size()}; }
Eigen::Map<const Eigen::VectorXd> flat(const Positions& P) { return {P.data(), P.size()}; }

void mask_pinned(const ClothSystem& s, Positions& f)
{
    for (int i = 0; i < s.vertex_count(); ++i)
        if (s.pinned(i)) f.row(i).setZero();
}

double weight_norm(const ClothSystem& s)
{
    const Positions g = s.gravity_forces();
    const double w = flat(g).norm();
    return w > 0 ? w : 1.0;
}

/// Damping "energy" 1/2 V^T D V for the implicit step (D = dashpots + air).
double damping_quadratic(const ClothSystem& s, const Positions& X, const Positions& V)
{
    Positions f = Positions::Zero(X.rows(), 3);
    s.add_damping_forces(X, V, f);
    return -0.5 * flat(V).dot(flat(f));
}

/// The last symbolic analysis made on this thread, kept for the next static
/// solve of the same sparsity pattern: a warm re-solve (a fit's next
/// evaluation, simulate_drape_from) builds a new system on the same mesh, and
/// METIS costs 50 ms at 23k unknowns, about one Newton iteration. The factor's
/// memory (30 MB at 23k unknowns) stays with the thread until a solve of
/// another pattern replaces it. A solve takes the object out while it runs.
struct AnalysedPattern {
    std::vector<int> outer, inner;
    std::unique_ptr<Cholmod> llt;
    bool matches(const SpMat& A) const
    {
        return llt && outer.size() == static_cast<std::size_t>(A.outerSize() + 1) && inner.size() == static_cast<std::size_t>(A.nonZeros()) &&
               std::equal(outer.begin(), outer.end(), A.outerIndexPtr()) && std::equal(inner.begin(), inner.end(), A.innerIndexPtr());
    }
};
thread_local AnalysedPattern t_last_analysis;

/// A Cholesky object analysed for A's pattern: this thread's last one when the
/// pattern matches (`reused` true), a fresh analysis otherwise.
std::unique_ptr<Cholmod> take_analysed(const SpMat& A, bool& reused)
{
    AnalysedPattern& last = t_last_analysis;
    reused = last.matches(A);
    if (reused) return std::move(last.llt);
    last.llt.reset(); // free the old factor before the new analysis
    auto llt = std::make_unique<Cholmod>();
    configure_cholmod(*llt);
    llt->analyzePattern(A);
    return llt;
}

/// Keeps `llt` (analysed for A's pattern) for this thread's next solve.
void keep_analysed(std::unique_ptr<Cholmod> llt, const SpMat& A)
{
    if (!llt) return;
    AnalysedPattern& last = t_last_analysis;
    last.outer.assign(A.outerIndexPtr(), A.outerIndexPtr() + A.outerSize() + 1);
    last.inner.assign(A.innerIndexPtr(), A.innerIndexPtr() + A.nonZeros());
    last.llt = std::move(llt);
}

} // namespace

double relative_residual(const ClothSystem& s)
{
    Positions f;
    s.conservative_forces(s.x, f);
    mask_pinned(s, f);
    return flat(f).norm() / weight_norm(s);
}

// ---- Stepper -----------------------------------------------------------------

struct Stepper::Impl {
    explicit Impl(const ClothSystem& s) : H(s) {}
    HessianAssembler H;
    Cholmod llt;
    bool analysed = false;
    long solves = 0;
    Positions f, k1x, k1v, k2x, k2v, k3x, k3v, k4x, k4v, xt, vt;
};

Stepper::Stepper(ClothSystem& s, Integrator integ) : m_s(s), m_integ(integ), m_impl(new Impl(s))
{
    if (integ == Integrator::Static) throw ParameterError("Stepper: the static solver has no time step; use run_to_rest");
}

Stepper::~Stepper() { delete m_impl; }

long Stepper::linear_solves() const { return m_impl->solves; }

double Stepper::explicit_dt_limit() const
{
    const auto& m = m_s.model();
    const int n = m_s.vertex_count();
    Eigen::VectorXd kk = m.contact_stiffness, dd = Eigen::VectorXd::Zero(n);
    for (const auto& sp : m.springs) {
        kk(sp.i) += 2 * sp.k;
        kk(sp.j) += 2 * sp.k;
        dd(sp.i) += 2 * sp.d;
        dd(sp.j) += 2 * sp.d;
    }
    for (const auto& b : m.bends) {
        double sw = 0;
        for (int a = 0; a < b.n; ++a) sw += std::abs(b.w[a]);
        for (int a = 0; a < b.n; ++a) {
            kk(b.v[a]) += b.k * std::abs(b.w[a]) * sw;
            dd(b.v[a]) += b.d * std::abs(b.w[a]) * sw;
        }
    }
    double w2 = 0, c = m.air_damping;
    for (int i = 0; i < n; ++i) {
        w2 = std::max(w2, kk(i) / m.mass(i));
        c = std::max(c, dd(i) / m.mass(i) + m.air_damping);
    }
    // Stability reach of each method on the imaginary (oscillation) and negative
    // real (damping) axes of the step-size plane.
    double im = 2.8, re = 2.78;
    switch (m_integ) {
    case Integrator::RK4: im = 2.8; re = 2.78; break;
    case Integrator::SemiImplicitEuler: im = 2.0; re = 2.0; break;
    case Integrator::Midpoint: im = 0.5; re = 2.0; break; // marginal on the imaginary axis: keep well inside
    case Integrator::ExplicitEuler: im = 0.1; re = 2.0; break; // unstable for undamped oscillation; damping saves it
    default: break;
    }
    const double w = std::sqrt(w2);
    double dt = std::numeric_limits<double>::infinity();
    if (w > 0) dt = std::min(dt, im / w);
    if (c > 0) dt = std::min(dt, re / c);
    return 0.9 * dt;
}

bool Stepper::step(double dt)
{
    auto& s = m_s;
    auto& I = *m_impl;
    const int n = s.vertex_count();
    const auto& mass = s.model().mass;
    auto accel = [&](const Positions& X, const Positions& V, Positions& A) {
        s.total_forces(X, V, A);
        for (int i = 0; i < n; ++i) A.row(i) /= mass(i);
    };
    auto zero_pinned = [&](Positions& P) { mask_pinned(s, P); };
    switch (m_integ) {
    case Integrator::ExplicitEuler: {
        accel(s.x, s.v, I.k1v);
        s.x += dt * s.v;
        s.v += dt * I.k1v;
        break;
    }
    case Integrator::SemiImplicitEuler: {
        accel(s.x, s.v, I.k1v);
        s.v += dt * I.k1v;
        zero_pinned(s.v);
        s.x += dt * s.v;
        break;
    }
    case Integrator::Midpoint: {
        accel(s.x, s.v, I.k1v);
        I.xt = s.x + 0.5 * dt * s.v;
        I.vt = s.v + 0.5 * dt * I.k1v;
        zero_pinned(I.vt);
        accel(I.xt, I.vt, I.k2v);
        s.x += dt * I.vt;
        s.v += dt * I.k2v;
        break;
    }
    case Integrator::RK4: {
        accel(s.x, s.v, I.k1v);
        I.k1x = s.v;
        I.xt = s.x + 0.5 * dt * I.k1x;
        I.vt = s.v + 0.5 * dt * I.k1v;
        zero_pinned(I.vt);
        accel(I.xt, I.vt, I.k2v);
        I.k2x = I.vt;
        I.xt = s.x + 0.5 * dt * I.k2x;
        I.vt = s.v + 0.5 * dt * I.k2v;
        zero_pinned(I.vt);
        accel(I.xt, I.vt, I.k3v);
        I.k3x = I.vt;
        I.xt = s.x + dt * I.k3x;
        I.vt = s.v + dt * I.k3v;
        zero_pinned(I.vt);
        accel(I.xt, I.vt, I.k4v);
        I.k4x = I.vt;
        s.x += dt / 6.0 * (I.k1x + 2 * I.k2x + 2 * I.k3x + I.k4x);
        s.v += dt / 6.0 * (I.k1v + 2 * I.k2v + 2 * I.k3v + I.k4v);
        break;
    }
    case Integrator::ImplicitEuler: {
        // Backward Euler as a minimisation (the incremental potential):
        //   y = argmin 1/(2 dt^2) |y - x_n - dt v_n|_M^2 + E(y) + dt/2 V^T D V - f_fric . (y - x_n),
        // with V = (y - x_n)/dt, D the dashpot matrix and friction explicit. Newton
        // with a projected (PSD) Hessian and a backtracking line search: stable at
        // any step (Baraff and Witkin 1998 take one such Newton step).
        const Positions xn = s.x, vn = s.v;
        Positions ffric = Positions::Zero(n, 3);
        s.add_friction_forces(xn, vn, ffric);
        const Positions pred = xn + dt * vn;
        Eigen::VectorXd md = mass / (dt * dt);
        auto phi = [&](const Positions& Y) {
            double e = s.potential_energy(Y);
            for (int i = 0; i < n; ++i) e += 0.5 * md(i) * (Y.row(i) - pred.row(i)).squaredNorm();
            const Positions V = (Y - xn) / dt;
            e += dt * damping_quadratic(s, Y, V);
            e -= flat(ffric).dot(flat(Positions(Y - xn)));
            return e;
        };
        Positions y = pred;
        for (int i = 0; i < n; ++i)
            if (s.pinned(i)) y.row(i) = xn.row(i);
        const double wn = weight_norm(s);
        for (int it = 0; it < m_implicit_iterations; ++it) {
            // Gradient of phi (negated: the force).
            Positions g;
            s.conservative_forces(y, g);
            ++s.force_evaluations;
            const Positions V = (y - xn) / dt;
            s.add_damping_forces(y, V, g);
            g += ffric;
            for (int i = 0; i < n; ++i) g.row(i) -= md(i) * (y.row(i) - pred.row(i));
            mask_pinned(s, g);
            if (flat(g).norm() < 1e-9 * wn) break;
            I.H.assemble(y, md, 1.0 / dt);
            if (!I.analysed) {
                configure_cholmod(I.llt);
                I.llt.analyzePattern(I.H.matrix());
                I.analysed = true;
            }
            I.llt.factorize(I.H.matrix());
            if (I.llt.info() != Eigen::Success) return false;
            Eigen::VectorXd dx = I.llt.solve(flat(g));
            ++I.solves;
            Positions D = Eigen::Map<Positions>(dx.data(), n, 3);
            const double p0 = phi(y);
            const double slope = -flat(g).dot(dx);
            double alpha = 1;
            Positions trial;
            for (int ls = 0; ls < 30; ++ls) {
                trial = y + alpha * D;
                if (phi(trial) <= p0 + 1e-4 * alpha * slope) break;
                alpha *= 0.5;
            }
            y = trial;
            if (alpha * dx.lpNorm<Eigen::Infinity>() < 1e-12) break;
        }
        s.v = (y - xn) / dt;
        s.x = y;
        break;
    }
    case Integrator::Static: return false;
    }
    zero_pinned(s.v);
    s.time += dt;
    return s.x.allFinite() && s.v.allFinite();
}

// ---- run to rest -------------------------------------------------------------

namespace {

using Clock = std::chrono::steady_clock;

bool cancelled(const RestOptions& opt, const SolverStatus& st)
{
    if (opt.cancel && opt.cancel->load()) return true;
    if (opt.progress && !opt.progress(st)) return true;
    return false;
}

SolverStatus run_dynamic(ClothSystem& s, const RestOptions& opt)
{
    SolverStatus st;
    const auto t0 = Clock::now();
    Stepper stepper(s, opt.integrator);
    double dt = opt.dt;
    if (dt <= 0) dt = opt.integrator == Integrator::ImplicitEuler ? 2e-3 : stepper.explicit_dt_limit();
    const long f0 = s.force_evaluations;
    const double e_scale = std::max(1e-12, s.model().total_mass() * 9.81 * 1.0); // 1 m drop of the whole cloth [J]
    const int check_every = 10;
    auto last_report = t0;
    while (true) {
        if (!stepper.step(dt)) {
            st.outcome = SolverStatus::Outcome::Diverged;
            st.message = "state became non-finite at t = " + std::to_string(s.time) + " s (dt = " + std::to_string(dt) + " s)";
            break;
        }
        ++st.steps;
        if (st.steps % check_every == 0) {
            st.max_speed = s.v.rowwise().norm().maxCoeff();
            const double ke = s.kinetic_energy(s.v);
            if (!std::isfinite(ke) || ke > 1e3 * e_scale) {
                st.outcome = SolverStatus::Outcome::Diverged;
                st.message = "kinetic energy blew up (" + std::to_string(ke) + " J) at t = " + std::to_string(s.time) + " s";
                break;
            }
            if (st.max_speed < opt.max_speed) {
                st.residual = relative_residual(s);
                if (st.residual < opt.residual) {
                    st.outcome = SolverStatus::Outcome::Converged;
                    break;
                }
            }
            const auto now = Clock::now();
            if (now - last_report > std::chrono::milliseconds(200)) {
                last_report = now;
                st.sim_time = s.time;
                st.force_evaluations = s.force_evaluations - f0;
                st.wall_seconds = std::chrono::duration<double>(now - t0).count();
                if (cancelled(opt, st)) {
                    st.outcome = SolverStatus::Outcome::Cancelled;
                    break;
                }
            }
            if (s.time >= opt.max_sim_time || st.steps >= opt.max_steps) {
                st.outcome = SolverStatus::Outcome::NotConverged;
                st.residual = relative_residual(s);
                st.message = "not at rest after " + std::to_string(s.time) + " s simulated (max speed " +
                             std::to_string(st.max_speed) + " m/s, residual " + std::to_string(st.residual) + ")";
                break;
            }
        }
    }
    st.max_speed = s.v.rowwise().norm().maxCoeff();
    if (st.outcome != SolverStatus::Outcome::Diverged) st.residual = relative_residual(s);
    st.sim_time = s.time;
    st.newton_iterations = stepper.linear_solves();
    st.force_evaluations = s.force_evaluations - f0;
    st.wall_seconds = std::chrono::duration<double>(Clock::now() - t0).count();
    return st;
}

/// Static solver: the rest state as a minimum of the potential energy, found by
/// Newton's method regularised with a proximal mass term M/h^2 (a fully damped
/// implicit step of pseudo-time h). h grows while full Newton steps are
/// accepted and shrinks when the line search cuts them, so the method behaves
/// like damped dynamics far from rest (the folds form as they would in a real
/// fall) and like pure Newton near it. The proximal term also removes the
/// neutral modes of a frictionless contact (sliding and spinning on the disc).
SolverStatus run_static(ClothSystem& s, const RestOptions& opt)
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
    const auto& mass = s.model().mass;
    const double wn = weight_norm(s);
    double h = opt.dt > 0 ? opt.dt : 0.02;
    const double h_max = 50.0, h_min = 1e-6;
    Positions f, trial;
    s.v.setZero();
    int exact_ok = 1;
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
        const bool exact = exact_ok > 0;
        H.assemble(s.x, md, 0.0, !exact);
        if (!llt_p) {
            bool reused = false;
            {
                ProfileScope timer(profiling ? &prof.analyse : nullptr);
                llt_p = take_analysed(H.matrix(), reused);
            }
            if (opt.trace)
                std::fprintf(stderr, "static solver: %ld unknowns, %ld Hessian entries, factor %g entries, %g flop per factorisation (ordering %s%s)\n",
                             (long)H.matrix().rows(), (long)H.matrix().nonZeros(), llt_p->cholmod().lnz, llt_p->cholmod().fl,
                             llt_p->cholmod().method[llt_p->cholmod().selected].ordering == CHOLMOD_METIS ? "METIS" : "other",
                             reused ? ", analysis reused" : "");
        }
        Cholmod& llt = *llt_p;
        {
            ProfileScope timer(profiling ? &prof.factorize : nullptr);
            llt.factorize(H.matrix());
        }
        ++st.steps;
        if (llt.info() != Eigen::Success) ++prof.failed_factorizations;
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

} // namespace

SolverStatus run_to_rest(ClothSystem& s, const RestOptions& opt)
{
    if (opt.integrator == Integrator::Static) return run_static(s, opt);
    return run_dynamic(s, opt);
}

} // namespace drape::cloth
