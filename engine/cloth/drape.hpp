#pragma once
// The drapemeter experiment: a round specimen centred on a pedestal, draped to
// rest, measured with the shared metric code.
#include "engine/cloth/metrics.hpp"
#include "engine/cloth/model.hpp"
#include "engine/cloth/params.hpp"
#include "engine/cloth/solver.hpp"

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>

namespace drape::cloth {

/// The specimen's mesh on the drapemeter (DrapeSetup::mesh).
enum class DrapeMesh {
    /// make_disc: the seed's square lattice, the grid model (warp/weft springs,
    /// lattice bending stencils).
    Grid,
    /// make_ring_disc graded at the pedestal's rim (drapemeter_rim_grading):
    /// concentric rings through the general triangle model, the spacing 0.4 of
    /// the nominal one where the cloth bends over the rim and the folds root.
    /// The bend over the rim is about sqrt(B / T) wide (T the tension the
    /// overhang hangs on the rim with): 3.5-14 mm for the starters, below the
    /// nominal spacing of grid 41 (7.5 mm) for limp fabrics, where the grid's D
    /// moves with the grid (docs/decisions/0019-drapemeter-mesh.md).
    Rings,
};
const char* to_string(DrapeMesh m);
/// "grid" or "rings"; ParameterError naming the value otherwise.
DrapeMesh drape_mesh_from_string(const std::string& s);

/// DrapeSetup::perturbation's default [m]: the largest lift of the flat
/// sheet's seeded waviness when nothing states it (the engine's, the starters').
/// A fitted preset carries its lab's (Provenance::perturbation_m,
/// `drape fit --perturbation`).
inline constexpr double kStartLift = 1.0e-3;

struct DrapeSetup {
    double sample_diameter = 0.30;  ///< [m]
    double disc_diameter = 0.15;    ///< [m]
    double pedestal_height = 0.12;  ///< [m]
    double edge_radius = 0.5e-3;    ///< [m] rounding of the pedestal's top edge
    int grid = 60;                  ///< nodes across the specimen diameter (rings: the nominal spacing is that of this grid)
    DrapeMesh mesh = DrapeMesh::Grid; ///< the specimen's mesh
    std::uint64_t seed = 1;         ///< perturbation seed (buckling is a bifurcation)
    /// Amplitude of the symmetry-breaking perturbation [m]: the flat sheet's
    /// height gets sum_k a_k cos(k theta + phi_k) t^2 for k = 2..16, with
    /// t = (r - R2) / (R1 - R2) on the overhang (0 on the disc), random a_k in
    /// [0,1] normalised so the largest lift is this amplitude, and random
    /// phases, all from `seed`. Small enough not to change a converged D
    /// beyond the spread of real repeats, large enough to pick a fold pattern.
    double perturbation = kStartLift;
    /// 0: the seeded mix above. n >= 2: start on an n-fold branch - the lift is
    /// cos(n theta + phi) t^2 (t as above) with a seeded phase phi, plus the seeded mix at
    /// a tenth of the amplitude so the n-fold symmetry is not exact. Whether the
    /// sheet keeps n folds is then up to the fabric: an unstable branch buckles
    /// into another count on the way to rest.
    int fold_mode = 0;
    /// n-fold start (fold_mode >= 2): the angle [rad] of one of its crests from
    /// +x (warp) towards +y; NaN: the seeded phase. The folds rest near the angle
    /// they start at, and on an anisotropic fabric that angle moves the rest
    /// state's cos 2theta contour term by millimetres and D by about a point
    /// (docs/model-discrepancy.md, "What the residual still shows"). `drape fit` keeps the seeded
    /// phase: its seeds' spread then carries that angle's effect into the noise.
    double fold_angle = std::numeric_limits<double>::quiet_NaN();
    /// How the specimen is laid (the lab's hand, not the fabric): the static
    /// drape from flat first comes to rest under this fraction of gravity, then
    /// under full gravity from there. 1: the whole load at once (the engine's
    /// default, and what every drape before 2026-11-30 did). A lighter first
    /// load lets the overhang buckle into fewer, wider folds, as a specimen laid
    /// with its rim partly held does; kLabLaying (0.4) is the drape lab's, which
    /// `drape fit` writes into its presets (docs/decisions/0013-laying-0-4.md). Only the static path,
    /// and with the continuation only its coarsest level (the finer ones start
    /// from that rest state). In (0, 1].
    double laying_load = 1.0;
    bool floor = true;
    /// Full grip on the disc (the limit of large static friction): every vertex
    /// laid on the disc top is tethered horizontally where it was laid. Off by
    /// default: only the centre is held (the seed's disc is frictionless; see
    /// HorizontalAnchor); docs/decisions/0008-disc-friction-not-fitted.md.
    bool disc_grip = false;
    /// The specimen laid off centre [m] (x, y): its centre (and the grip of the
    /// disc, when on) this far from the pedestal axis: a lab error, 0 by default. Not
    /// an effect the fit tests: on the frictionless disc it turns the fold pattern by a
    /// step-dependent angle, so it has no usable first-order signature.
    Eigen::Vector2d specimen_offset = Eigen::Vector2d::Zero();
    /// A specimen whose areal density varies across it (x, y): the relative
    /// change per specimen radius, rho(X) = rho (1 + g . X / R1) on the flat
    /// sheet (the mean is unchanged). |g| < 1; 0 by default.
    Eigen::Vector2d density_gradient = Eigen::Vector2d::Zero();
    std::vector<double> slice_depths = {0.005, 0.01, 0.015, 0.02, 0.025, 0.03, 0.035, 0.04, 0.045, 0.05}; ///< [m] below the pedestal top
    void validate() const;          ///< ParameterError on negative sizes, sample <= disc, grid < 5, fold_mode 1 or > 16, an infinite fold_angle, an offset off the disc, |density gradient| >= 1
};

/// Default lift of an n-fold start [m] (DrapeSetup::fold_mode): the static
/// solver's path from flat loses a 1-3 mm lift on some seeds (the count then
/// comes out as from the random mix); 8 mm and more leave the linear range
/// (folds split or merge); 5 mm kept the branch on set-a presets
/// (docs/decisions/0002-fold-branch-measured.md).
inline constexpr double kFoldBranchLift = 5e-3;

/// `s` set to start on the n-fold branch: fold_mode = n, perturbation = `lift_m`,
/// one crest at `angle` [rad] from the warp (NaN: the seeded phase).
inline DrapeSetup on_fold_branch(DrapeSetup s, int n, double lift_m = kFoldBranchLift,
                                 double angle = std::numeric_limits<double>::quiet_NaN())
{
    s.fold_mode = n;
    s.perturbation = lift_m;
    s.fold_angle = angle;
    return s;
}

/// The coarsest grid DrapeMesh::Rings takes (DrapeSetup::validate).
inline constexpr int kMinRingsGrid = 17;

/// Where DrapeMesh::Rings refines, from the pedestal's geometry alone (not the
/// fabric, so a fit's objective does not jump with the mesh): 10 mm inside the
/// disc's edge to 15 mm outside it at 0.4 of the nominal spacing, tapering over
/// 15 mm (the bend over the rim and the folds' roots; chosen on the drapemeter's
/// geometry, not fitted: docs/decisions/0019-drapemeter-mesh.md).
RingGrading drapemeter_rim_grading(const DrapeSetup& setup);

/// The specimen's flat mesh for `setup` (setup.mesh at setup.grid), centre at the origin.
ClothMesh make_drape_mesh(const DrapeSetup& setup);

/// Builds the drape scene: disc mesh (or the material's own grid when it has
/// grid springs), model, pedestal and floor colliders, perturbed flat start.
std::unique_ptr<ClothSystem> make_drape_system(const Material& fabric, const DrapeSetup& setup, const ModelOptions& mopt = {});

/// What make_drape_system does to its disc, for a sheet built elsewhere (e.g. the
/// widget's square sheet, centred on the pedestal axis): lays it flat just above
/// the pedestal top, lifts it by the seeded perturbation (DrapeSetup::perturbation,
/// fold_mode) and adds the pedestal and floor colliders.
void place_on_drapemeter(ClothSystem& sys, const DrapeSetup& setup);

struct Slice {
    double depth_m;
    RadialProfile profile; ///< NaN where the ray misses; complete() when closed
};

struct DrapeResult {
    SolverStatus status;
    Positions x;            ///< rest positions [m]
    DrapeMetrics metrics;   ///< shadow metrics
    Polygon2 outline;       ///< shadow outline [m]
    HemProfile hem;
    std::vector<Slice> slices;
    double potential_energy = 0; ///< [J] of the rest state (springs or membrane, bending, gravity, contact): compares fold branches; set by simulate_drape(_from), not by measure_drape
};

/// Measures a draped system (shadow, hem, slices) through the shared metric code.
DrapeResult measure_drape(const ClothSystem& s, const DrapeSetup& setup, const MetricOptions& mopt = {});

/// The coarsest level of simulate_drape's continuation (7.5 mm cells on 300 mm):
/// the grid where a drape from flat chooses its fold branch for every finer grid
/// (docs/decisions/0012-coarsest-level-41.md).
inline constexpr int kCoarsestLevel = 41;

/// RestOptions::shift_before_projection of the continuation's finer levels [s]:
/// the proximal shift M / h^2 grows to m / (0.01 s)^2 per vertex (a stiffness of
/// 10^4 s^-2 times its mass) before the static solver projects curvature away.
inline constexpr double kFineShiftPseudoTime = 0.01;

/// DrapeSetup::laying_load of the drape lab's tests: what `drape fit` assumes
/// of the records' lab by default (--laying) for its drapes from flat, and
/// writes into the fitted preset (fabric::Provenance::laying_load), so that
/// `drape simulate`, `predict` and the widget lay that preset as its lab did.
/// Chosen on the lab's set-a records (their fitted presets of 2026-11-30 from
/// flat at grids 41, 61, 81; candidates 0.2, 0.3, 0.4, 0.5 and 1) by the loss
/// |D - lab D| / 2 points + |folds - lab folds| (the tolerances),
/// leave-one-out: each of the ten held-out records got 0.4 from the other
/// nine, and held out its from-flat |D error| went 3.41 -> 2.18 points, the
/// |fold error| 1.20 -> 0.70 against the whole load at once
/// (docs/decisions/0013-laying-0-4.md). A lab's value, not a fabric's: presets without it (the
/// starters) are laid at once.
inline constexpr double kLabLaying = 0.4;

/// DrapeSetup::perturbation of the drape lab's tests: how wavy its specimens
/// lie when laid, what `drape fit` assumes by default (--perturbation) for its
/// drapes from flat and writes into the preset (fabric::Provenance::perturbation_m),
/// as kLabLaying. Chosen on the lab's set-a records like the laying: each
/// record fitted at 1, 3, 6 and 10 mm (2026-12-01), its preset draped
/// from flat with seeds 1-3 at grids 41 and 61 and seed 1 at 81, loss
/// |D - lab D| / 2 points + |folds - lab folds| over those seven drapes; leave-
/// one-out, nine held-out records got 6 mm from the other nine (one got 3), and
/// held out the from-flat |D error| went 2.02 -> 1.63 points, the loss 2.03 ->
/// 1.93, the drapes within 2 points and 1 fold 44 -> 57 %, while the |fold
/// error| went 1.01 -> 1.11 against 1 mm (docs/decisions/0021-perturbation-6mm.md).
/// A lab's value, not a fabric's: presets without it (the starters) keep
/// kStartLift.
inline constexpr double kLabWaviness = 0.006;

/// Interpolates positions of a coarse grid disc onto a finer one through their
/// shared material coordinates (barycentric in the containing or nearest coarse
/// triangle, extrapolating linearly at the hem): how a rest state is carried to
/// the next level of the continuation.
Positions interpolate_positions(const ClothMesh& coarse, const Positions& xc, const ClothMesh& fine);

/// `ropt` as a drape of `setup` from its start uses it: with the late shift
/// near rest (RestOptions::late_shift_residual = kLateShiftResidual) when the
/// start is the random mix (fold_mode 0) and the caller left it 0. Used by
/// rest_from_flat and simulate_drape.
RestOptions from_flat_options(RestOptions ropt, const DrapeSetup& setup);

/// The drape of `sys` (made by make_drape_system for `setup`, at its start) to
/// rest on its own mesh, laid as the set-up says: with the static solver and
/// laying_load < 1 a first rest under that fraction of gravity (residual
/// 1e-4 or the options', whichever is larger), then run_to_rest under the
/// whole load; counters summed. Otherwise run_to_rest. Options as
/// from_flat_options makes them. What simulate_drape does below the
/// continuation's coarsest level, and the widget on its own system (live frames).
SolverStatus rest_from_flat(ClothSystem& sys, const DrapeSetup& setup, const RestOptions& ropt);

/// The relative force residual a continuation's coarser level is solved to
/// before the finer level polishes (or RestOptions::residual, when larger).
inline constexpr double kLevelResidual = 1e-4;

/// The continuation's level simulate_drape solves first for `grid` (the largest
/// of kCoarsestLevel, 81, 161, 321, ... below it); 0 when `grid` is drawn
/// directly (kCoarsestLevel or coarser).
int continuation_level(int grid);

/// A rest of one of the continuation's levels (kCoarsestLevel, 81, 161, ...),
/// as simulate_drape solves it on the way to a finer grid: what a finer drape
/// of the same fabric and set-up can start from instead of solving it again.
struct LevelRest {
    int grid = 0;        ///< the level's grid
    double residual = 0; ///< the residual it was solved to: max(RestOptions::residual, kLevelResidual)
    Positions x;         ///< [m]
    SolverStatus status; ///< of the drape up to it (its laying and coarser levels included)
};

/// Simulates a drape to rest and measures it. For the static solver with a
/// grid finer than kCoarsestLevel (41) this solves the largest of the levels 41,
/// 81, 161, 321 below it first and interpolates (continuation): the cold start
/// stays fast, and every finer grid shows the fold branch grid 41 takes from flat.
/// Options as from_flat_options makes them (the late shift from the random mix).
///
/// `levels`, when given, collects the level rests the drape solved: its coarser
/// level's (not when it started from `start`), and its own grid's when that is a level (the iterate where its
/// residual first fell below the level's residual - the iterate the level's solve
/// would stop at; the path is unchanged). `start`, when given, is the rest of
/// this drape's coarser level from an earlier drape of the same fabric, set-up
/// (grid aside), rest and model options: the drape polishes from it instead of
/// solving that level again - the same result, since the level's solve is
/// deterministic (tst_drape continuationFromAKeptLevelIsTheSameDrape). A `start`
/// of another level or residual is not used.
DrapeResult simulate_drape(const Material& fabric, const DrapeSetup& setup, const RestOptions& ropt = {},
                           const ModelOptions& mopt = {}, const LevelRest* start = nullptr, std::vector<LevelRest>* levels = nullptr);

/// Warm start: re-solve from a previous rest state (same mesh), e.g. after a
/// small parameter change during a fit.
DrapeResult simulate_drape_from(const Material& fabric, const DrapeSetup& setup, const Positions& start,
                                const RestOptions& ropt = {}, const ModelOptions& mopt = {});

} // namespace drape::cloth
