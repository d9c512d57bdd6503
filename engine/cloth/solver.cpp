#include "engine/cloth/solver.hpp"

#include "engine/cloth/solver_detail.hpp"
#include "engine/cloth/sparse_cholesky.hpp"
#include "engine/core/error.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <memory>

namespace drape::cloth {

using namespace detail;

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

/// Damping "energy" 1/2 V^T D V for the implicit step (D = dashpots + air).
double damping_quadratic(const ClothSystem& s, const Positions& X, const Positions& V)
{
    Positions f = Positions::Zero(X.rows(), 3);
    s.add_damping_forces(X, V, f);
    return -0.5 * flat(V).dot(flat(f));
}

} // namespace

double relative_residual(const ClothSystem& s, bool self_contact)
{
    Positions f;
    s.conservative_forces(s.x, f);
    if (!self_contact)
        for (const auto& p : s.self_contact_pairs(s.x)) {
            Vec12 g;
            s.self_contact_pair_energy(p, s.x, &g);
            for (int a = 0; a < 4; ++a) f.row(p.v[static_cast<std::size_t>(a)]) += g.segment<3>(3 * a).transpose();
        }
    mask_pinned(s, f);
    return flat(f).norm() / weight_norm(s);
}

// ---- Stepper -----------------------------------------------------------------

struct Stepper::Impl {
    explicit Impl(const ClothSystem& s) : H(s) {}
    HessianAssembler H;
    std::unique_ptr<Cholmod> llt; ///< analysed on the first implicit step
    int analysed_revision = -1;   ///< H's pattern revision llt was analysed for
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
    for (const auto& fb : m.fibers) {
        const double sw = std::abs(fb.w[0]) + std::abs(fb.w[1]) + std::abs(fb.w[2]);
        for (int a = 0; a < 3; ++a) {
            kk(fb.v[a]) += fb.k * std::abs(fb.w[a]) * sw;
            dd(fb.v[a]) += fb.d * std::abs(fb.w[a]) * sw;
        }
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

namespace {

/// Explicit integrators step without the self-contact barrier: it is infinite
/// at touching, and only a step filter (the implicit and static paths have
/// one) keeps a step from jumping over it (ModelOptions::self_collision).
class SelfContactOff {
public:
    SelfContactOff(ClothSystem& s, bool off) : m_s(s), m_d(s.model().self_contact_distance)
    {
        if (off) m_s.model().self_contact_distance = 0;
    }
    ~SelfContactOff() { m_s.model().self_contact_distance = m_d; }
    SelfContactOff(const SelfContactOff&) = delete;
    SelfContactOff& operator=(const SelfContactOff&) = delete;

private:
    ClothSystem& m_s;
    double m_d;
};

} // namespace

bool Stepper::step(double dt)
{
    auto& s = m_s;
    auto& I = *m_impl;
    const SelfContactOff explicit_step(s, m_integ != Integrator::ImplicitEuler);
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
        // The prediction is a step too: cut it where it would carry one part of
        // the cloth through another (the barrier would then hold the crossing).
        if (s.self_contact_on()) y = xn + s.self_contact_step_bound(xn, Positions(y - xn)) * (y - xn);
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
            if (!I.llt || I.H.revision() != I.analysed_revision) {
                I.analysed_revision = I.H.revision();
                bool reused = false;
                I.llt = take_analysed(I.H.matrix(), reused);
            }
            I.llt->factorize(I.H.matrix());
            if (I.llt->info() != Eigen::Success) return false;
            Eigen::VectorXd dx = I.llt->solve(flat(g));
            ++I.solves;
            Positions D = Eigen::Map<Positions>(dx.data(), n, 3);
            const double p0 = phi(y);
            const double slope = -flat(g).dot(dx);
            double alpha = s.self_contact_step_bound(y, D);
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

} // namespace

SolverStatus run_to_rest(ClothSystem& s, const RestOptions& opt)
{
    if (opt.integrator == Integrator::Static) return detail::run_static(s, opt);
    // Explicit integrators run without the barrier (Stepper::step), and so does
    // their rest test (the residual would otherwise count barrier forces of
    // layers the explicit steps let come closer than the contact distance).
    const SelfContactOff explicit_run(s, opt.integrator != Integrator::ImplicitEuler);
    return run_dynamic(s, opt);
}

} // namespace drape::cloth
