#pragma once
// Time integrators and the static (rest-state) solver.
#include "engine/cloth/system.hpp"

#include <atomic>
#include <functional>
#include <string>

namespace drape::cloth {

enum class Integrator { ExplicitEuler, SemiImplicitEuler, Midpoint, RK4, ImplicitEuler, Static };

/// "euler" (explicit), "symplectic" (semi-implicit), "midpoint", "rk4", "implicit", "static".
Integrator parse_integrator(const std::string& name);
std::string to_string(Integrator i);

struct SolverStatus {
    enum class Outcome { Running, Converged, NotConverged, Diverged, Cancelled };
    Outcome outcome = Outcome::Running;
    long steps = 0;              ///< time steps (dynamic) or outer iterations (static)
    long newton_iterations = 0;  ///< linear solves
    long force_evaluations = 0;
    double max_speed = 0;        ///< [m/s]
    double residual = 0;         ///< relative force residual |f_net| / |weight|
    double wall_seconds = 0;
    double sim_time = 0;         ///< [s] simulated time (dynamic)
    std::string message;
    bool converged() const { return outcome == Outcome::Converged; }
    /// Adds the work of an earlier solve of the same drape (steps, Newton
    /// iterations, force evaluations, wall time): a continuation's coarse level,
    /// a laying rest.
    void add_work(const SolverStatus& earlier)
    {
        steps += earlier.steps;
        newton_iterations += earlier.newton_iterations;
        force_evaluations += earlier.force_evaluations;
        wall_seconds += earlier.wall_seconds;
    }
    /// Time steps (dynamic) or Newton iterations (static).
    long integrator_steps() const { return newton_iterations > 0 && sim_time == 0 ? newton_iterations : steps; }
};
std::string to_string(SolverStatus::Outcome o);

struct RestOptions {
    Integrator integrator = Integrator::Static;
    double dt = 0;                ///< time step [s]; 0 = choose (explicit: stability estimate)
    double max_speed = 1e-3;      ///< rest when every vertex is slower [m/s] (dynamic integrators)
    double residual = 1e-6;       ///< and the relative force residual is below this
    double max_sim_time = 60;     ///< give up after this much simulated time [s]
    long max_steps = 5'000'000;
    long max_newton = 1000;        ///< static solver
    bool trace = false;           ///< print each static iteration to stderr (residual, step, worst vertex)
    /// Static solver: when the exact Hessian does not factorise, first shrink the
    /// proximal pseudo-time h (a larger mass-weighted shift M / h^2 on the exact
    /// Hessian) down to this [s] before dropping curvature terms (projection).
    /// 0 = off: straight to the projected Hessian, as a drape from flat has always
    /// done (its path picks the fold branch, so it is kept); simulate_drape then
    /// sets kFineShiftPseudoTime for the finer levels of its continuation that start
    /// on the coarser level's rest (they only polish its branch). Negative: off on
    /// those levels too. A positive value given to simulate_drape applies to every
    /// level, the coarsest one from flat included (which may change its branch).
    /// Failed factorisations on the way count as SolverStatus::steps, not as
    /// newton_iterations.
    double shift_before_projection = 0;
    /// Static solver, near rest: where the relative force residual is already below
    /// this, a failed exact factorisation also shrinks h first (down to
    /// kLateShiftPseudoTime) before the projected Hessian is used. The fold branch
    /// is chosen far from rest; near rest an indefinite exact Hessian is a saddle
    /// the drape leaves along its negative curvature, which the projected Hessian
    /// does not see: it crept off such a saddle for 600 iterations (a grid-41 drape
    /// of DL-A08's preset, 924 Newton iterations; 332 with the shift, the same rest
    /// state; docs/decisions/0023-late-shift-from-flat.md). 0: the solver does not
    /// (warm re-solves, a prescribed fold branch, garments - as before 2026-12-02);
    /// from_flat_options (drape.hpp: simulate_drape, rest_from_flat) then sets
    /// kLateShiftResidual for a drape from the random mix (DrapeSetup::fold_mode 0).
    /// Negative: off there too; so is a negative shift_before_projection.
    double late_shift_residual = 0;
    /// Static solver: called once with the iterate where the relative force
    /// residual first falls below `checkpoint_residual` (> 0) and the status a
    /// solve to that residual would end with (converged), before the solver goes
    /// on; the path is the same as without it. rest_from_flat calls it from the
    /// whole load's solve (its laying's work added); simulate_drape does not call
    /// a caller's, it keeps a continuation level's rest this way (LevelRest, drape.hpp).
    double checkpoint_residual = 0;
    std::function<void(const Positions&, const SolverStatus&)> checkpoint;
    /// Called now and then with the status so far; return false to cancel.
    std::function<bool(const SolverStatus&)> progress;
    const std::atomic<bool>* cancel = nullptr;
};

/// The floor of the pseudo-time h when the static solver shifts the exact Hessian
/// near rest (RestOptions::late_shift_residual) [s]: the proximal shift M / h^2
/// grows to m / (0.01 s)^2 per vertex, as on a continuation's finer levels
/// (kFineShiftPseudoTime, drape.hpp).
inline constexpr double kLateShiftPseudoTime = 0.01;

/// RestOptions::late_shift_residual of a drape from the random mix
/// (from_flat_options, fold_mode 0): forces below 1 % of the weight. On 60 drapes
/// of the set-a presets from flat (grids 41 and 61, 4 + 2 seeds) the fold count
/// and D were the same at 1e-3, 1e-2 and 1e-1 (one D moved by 0.06 point), one
/// fold count changed at 1; Newton iterations -4 %, -8 %, -13 %.
inline constexpr double kLateShiftResidual = 1e-2;

/// Advances the system by one step of `dt` with an explicit or implicit integrator.
/// Returns false when the state became non-finite. `scratch` avoids reallocation.
class Stepper {
public:
    Stepper(ClothSystem& s, Integrator integ);
    ~Stepper();
    bool step(double dt);
    /// Largest stable explicit step estimate [s] (highest spring/contact frequency).
    double explicit_dt_limit() const;
    Integrator integrator() const { return m_integ; }
    long linear_solves() const;
    /// Newton iterations per implicit Euler step (1 = Baraff and Witkin's single
    /// linearisation; more = closer to the exact backward Euler step). Default 2.
    void set_implicit_iterations(int n) { m_implicit_iterations = n < 1 ? 1 : n; }

private:
    struct Impl;
    ClothSystem& m_s;
    Integrator m_integ;
    Impl* m_impl;
    int m_implicit_iterations = 2;
};

/// Runs until rest (or failure): dynamic integration with a rest test, or the
/// static solver. Never throws on numerical trouble; the status says what happened.
SolverStatus run_to_rest(ClothSystem& s, const RestOptions& opt);

/// Relative force residual of the current state: |f_net| / |weight| over free vertices.
/// `self_contact` false leaves the self-contact barrier's forces out: the rest
/// test of an explicit integrator, which steps without the barrier.
double relative_residual(const ClothSystem& s, bool self_contact = true);

} // namespace drape::cloth
