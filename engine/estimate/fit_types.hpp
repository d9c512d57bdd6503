#pragma once
// The fit's vocabulary: its options, progress, result and the policies' names
// (fold branch, method, bending tie, shear hold, priors). The evaluator and the
// stages below the orchestrator (fit.hpp) read these; nothing here runs a fit.
#include "engine/estimate/measured.hpp"
#include "engine/estimate/objective.hpp"
#include "engine/estimate/residual.hpp"

#include "engine/cloth/drape.hpp"
#include "engine/cloth/params.hpp"

#include <Eigen/Core>

#include <atomic>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace drape::estimate {

/// The stages of a fit, in the order they run (docs/estimate.md "Stages in order").
enum class Stage {
    Start,              ///< the start point's evaluation
    Scan,               ///< a common bending's root on D
    Global,             ///< CRS2 (--method nlopt)
    Local,              ///< Levenberg-Marquardt, or BOBYQA
    Mirror,             ///< the warp/weft-swapped point
    Jacobian,           ///< re-solves of a Jacobian's columns the sensitivities do not serve
    Shear,              ///< the shear hold's refit
    Spread,             ///< extra seeds at the optimum
    Uncertainty,        ///< the intervals' Jacobian
    FromFlat,           ///< the kept result's drapes from flat
    FromFlatFoldCount,  ///< a fold-count step of the flat calibration, from flat
    FromFlatCalibrated, ///< a D step of the flat calibration, from flat
    Effects,            ///< the candidate effects' tests
    PresetAsSaved,      ///< the saved preset draped as the fit drapes
    Done,               ///< the fit's last report
};

/// A stage's name in the progress line, the trace and report.json ("from flat, fold count").
const char* to_string(Stage s);

struct FitProgress {
    /// The stage's name, after a later run's prefix ("tie ", "refine ") when it runs
    /// on behalf of the first: "scan", "tie local", "from flat, calibrated", "done".
    std::string stage;
    Stage stage_id = Stage::Start; ///< the stage itself, without the prefix
    int evaluation = 0;     ///< objective evaluations so far (all stages)
    int planned = 0;        ///< upper bound on evaluations of the whole fit
    double best_chi2 = 0;   ///< best sum of squared whitened residuals so far
    long simulations = 0;
    long unconverged = 0;   ///< simulations so far that did not come to rest
    double elapsed_s = 0;
    /// Search coordinates of the last evaluation (log10 of the value for log-scaled
    /// parameters, see FitVariable), in the order of fit_variables().
    std::vector<double> last_coords;
    /// False in the stages after the search (the drapes from flat, the effect
    /// tests, the calibration from flat) and in the last report ("done"): they draw drapes, not evaluations, so
    /// `evaluation` / `planned` says nothing of them - a caller that shows a
    /// fraction of the fit done has none to show there.
    bool search = true;
    /// True when the stage is about to start (its drapes are running), false when
    /// it has just drawn one: the long drapes after the search are announced first.
    bool starting = false;
};

/// Where a fit's cold simulations start (the node-count bifurcation).
enum class FoldBranch {
    /// On the record's measured branch: the flat sheet is lifted by an n-fold
    /// cosine (n = the record's measured node count, DrapeSetup::fold_mode), so
    /// D and the contours are compared between drapes with the same number of
    /// folds; whether the branch holds at the candidate parameters is the
    /// node-count term. Records without a node count start as `Random`.
    Measured,
    /// From the seeded random mix of modes (`drape predict`'s start): the fold
    /// count is whatever the perturbation seeds pick.
    Random,
    /// Both: the evaluation's even perturbation seeds start on the measured
    /// branch, the odd ones from the random mix, so the fit matches the record
    /// with the fold count it has and as the preset drapes from flat.
    Mixed,
};

std::string to_string(FoldBranch b);

/// How the fit searches after the scan of a common bending.
enum class FitMethod {
    /// Levenberg-Marquardt on the exact rest-state sensitivities: a
    /// handful of warm drapes, each linearised by one factorisation of its
    /// Hessian; the intervals come from the same exact Jacobian.
    Sensitivity,
    /// The derivative-free search of the first fits: NLopt's CRS2 (global) then
    /// BOBYQA (local), intervals from central differences of re-solves.
    Nlopt,
};
std::string to_string(FitMethod m);
FitMethod parse_fit_method(const std::string& name); ///< "lm" | "nlopt"; ParameterError otherwise
FoldBranch parse_fold_branch(const std::string& name); ///< "measured" | "random" | "mixed"; ParameterError otherwise

/// Warp and weft bending: fitted apart, tied (one bending, isotropic), or apart
/// and then tested: when the free fit's warp/weft ratio is beyond the
/// typical range of woven fabrics (kTypicalBendingAnisotropy) but its own 95 %
/// interval of the ratio holds 1 (the data do not separate the two), the fit is
/// repeated with the two tied (on the free fit's final sigmas), and the tied
/// preset is kept unless the likelihood ratio says the data need the anisotropy:
/// chi2 rises by more than 9, the 3-sigma quantile of chi2 with one degree of
/// freedom (the effect tests' level), after scaling by the free fit's chi2 / dof
/// when that exceeds 1.
enum class BendingTie { Auto, Free, Tied };
std::string to_string(BendingTie t);
BendingTie parse_bending_tie(const std::string& name); ///< "auto" | "free" | "tied"; ParameterError otherwise

/// Woven fabrics differ between warp and weft bending typically by less than a
/// factor of 3-4 (the starters' own ratios are 1.17-1.29). A fitted
/// ratio beyond this factor must be separated by the data, else BendingTie::Auto
/// tests the two tied.
inline constexpr double kTypicalBendingAnisotropy = 3.0;

/// In-plane shear: fitted, and held at the typical value when the data do not
/// constrain it (Auto), or fitted whatever the data say (Free). A drape test's
/// contours hardly see the shear stiffness (every set-a record's 95 % interval
/// spanned more than a decade, its value anywhere from 4 to the bound 1000 N/m
/// where the search happened to stop): a preset should not carry such a value
/// into a garment, where shear is what lets the cloth follow a body. Auto: when
/// the fitted shear's 95 % interval is open-ended (it runs into a fit bound, or
/// the shear is at one: the box, not the data, limits it), the fit moves it
/// to FitOptions::typical_shear_N_m, refits the other coordinates with it held,
/// and keeps the held fit unless chi2 rises by more than 9 (scaled by chi2 / dof
/// when that exceeds 1; the tie's 3-sigma level).
enum class ShearHold { Auto, Free };
std::string to_string(ShearHold h);
ShearHold parse_shear_hold(const std::string& name); ///< "auto" | "free"; ParameterError otherwise

/// The typical KES-FB1 shear rigidity of woven apparel fabrics, 1 gf/(cm*deg)
/// = 56.2 N/m per radian: the geometric middle of the 0.3..3 gf/(cm*deg) range
/// (17..170 N/m; Kawabata's measurements as summarised in textile handbooks,
/// cloth/params.cpp).
inline constexpr double kTypicalShearNm = 56.2;

/// Priors from real fabrics (docs/decisions/0029-priors-from-real-fabrics.md):
/// 251 woven and knitted fabrics measured by cantilever (Feng, Huang, Xu, Wang
/// 2022, "Learning-based bending stiffness parameter estimation by a drape
/// tester", SIGGRAPH Asia; summary figures only). Each enters the objective as
/// one Gaussian row in the search coordinates (log10), so a fit whose data do
/// not decide a direction lands where real fabrics are rather than in a corner
/// of the box; the report names the parameters the prior, not the data, decided.
struct FitPriors {
    /// log10(B warp / B weft) ~ N(0, sigma): their ratio has median 1.48 (|log10|
    /// 0.17), within a factor 2 for 62 %, 3 for 85 %, 5 for 96 %; a half-normal
    /// |log10 ratio| with sigma 0.3 decades puts 0.67 sigma = 0.2 at the median,
    /// 85 % within 0.43 (a factor 2.7) and 96 % within 0.62 (4.2): the data's
    /// spread with a lighter tail (the largest ratio, 11.9, is 3.6 sigma).
    double anisotropy_sigma_decades = 0.3;
    /// log10 of the mean bending (geometric mean of warp and weft) ~ N(centre, sigma):
    /// the fabrics span 2.2e-7 .. 2.7e-4 N*m, median ~1e-5 N*m; centre -5.0, sigma
    /// 0.6 decades puts that range at -2.7 .. +2.7 sigma (a weak prior: a drape's D
    /// pins the bending to ~0.1 decade).
    double bending_centre_log10_Nm = -5.0;
    double bending_sigma_decades = 0.6;
};

struct FitOptions {
    ModelVariant model = ModelVariant::Baseline;
    /// Add the priors (FitPriors) to the objective. Off in the library (the
    /// synthetic tests' truths are not drawn from real fabrics); `drape fit` turns
    /// them on unless --prior off.
    bool priors = false;
    FitPriors prior;
    FitMethod method = FitMethod::Sensitivity;
    int grid = 25;                ///< nodes across the specimen in the fit's simulations
    cloth::DrapeMesh mesh = cloth::DrapeMesh::Grid; ///< the specimen's mesh in the fit's simulations (at every grid it uses)
    std::uint64_t seed = 1;       ///< drives the optimizer's randomness and the perturbation seeds
    int seeds_per_evaluation = 2; ///< perturbation seeds averaged per evaluation (node-count bifurcation)
    int scan_evaluations = 6;     ///< at most, root search of a common bending on D before the global stage (0 = none)
    /// CRS2 budget; 0 = 4 per fitted coordinate (Nlopt), none (Sensitivity: a
    /// positive budget runs CRS2 before Levenberg-Marquardt).
    int global_evaluations = 0;
    /// Local budget: BOBYQA's (0 = 8 per coordinate + 8) or Levenberg-Marquardt's
    /// (0 = 4 per coordinate + 6 evaluations).
    int local_evaluations = 0;
    /// Global stage starts each simulation from the best point's rest state
    /// (faster; keeps each seed's fold pattern) instead of flat (cold).
    bool warm_global = true;
    /// The same for the local stage and the mirror check (and the Jacobian of
    /// the uncertainty stage, which always starts warm from the optimum).
    bool warm_local = true;
    bool uncertainty = true;      ///< Jacobian, covariance, intervals
    /// Test the candidate effects (effects.hpp) against the residual at the
    /// optimum: residual.candidates / named_effect (a few warm re-solves).
    bool effects = true;
    /// Extra perturbation seeds simulated at the optimum to measure the
    /// drape-to-drape spread of every residual term; sigmas below it are raised
    /// to it before the intervals are computed (0 = keep the default floors).
    int spread_seeds = 4;
    FoldBranch branch = FoldBranch::Measured;
    BendingTie bending = BendingTie::Auto;
    /// BendingTie::Auto tests the tie when the free ratio (or its inverse) exceeds this.
    double typical_bending_anisotropy = kTypicalBendingAnisotropy;
    ShearHold shear = ShearHold::Auto;
    /// ShearHold::Auto holds an unconstrained shear here [N/m] (a measured KES shear
    /// rigidity G in gf/(cm*deg) is G * 56.2 N/m).
    double typical_shear_N_m = kTypicalShearNm;
    /// > 0: the shear is not fitted but held at this value from the start [N/m] - the
    /// tied refit of BendingTie::Auto when the free fit held it (so that the tie's
    /// likelihood ratio compares the bendings on one shear, not the hold decided
    /// again on other sigmas); 0: as `shear` says.
    double shear_held_N_m = 0;
    /// Per residual term (in the evaluator's order): sigmas that replace the noise
    /// model's and the spread calibration's. The tied refit of BendingTie::Auto
    /// runs on the free fit's final sigmas, so that the two chi2 compare (each
    /// fit's own spread calibration draws other seeds; empty = not used).
    std::vector<double> term_sigmas;
    /// When the optimum is grid-bound (a fitted bending length below the mesh
    /// spacing), fit again on this finer grid from the coarse values; 0 = off
    /// (the library's default; `drape fit` refines to 41 unless --refine-grid 0).
    int refine_grid = 0;
    /// Largest lift of the n-fold start [m] (Measured branch). The static
    /// solver's path from flat is not the sheet's fall: a 1 mm lift (the random
    /// mix's) is lost on the way and the count comes out as from a random start;
    /// 20 mm is far outside the linear range and folds break up (docs/decisions/0002-fold-branch-measured.md).
    double branch_lift_m = cloth::kFoldBranchLift;
    /// DrapeSetup::laying_load of the drapes that start from the random mix (the
    /// `cold_*` report, records without a node count, the odd seeds of Mixed):
    /// how the lab lays a specimen. The n-fold starts are laid at once (1), so
    /// the branch is what they start on. 1 here (the library's default);
    /// `drape fit` passes cloth::kLabLaying unless --laying.
    double laying_load = 1.0;
    /// DrapeSetup::perturbation of the same drapes (the laid ones): how wavy the
    /// lab's specimens lie when laid, the largest lift [m] of the flat start's
    /// seeded waviness, in [0, 0.05]. The n-fold starts keep branch_lift_m.
    /// Written into the preset (provenance.perturbation_m) like laying_load.
    /// kStartLift here (the library's default); `drape fit` passes
    /// cloth::kLabWaviness unless --perturbation.
    double perturbation_m = cloth::kStartLift;
    /// Measured branch: perturbation seeds draped from the random mix at the
    /// optimum, reported as `cold_*` (what `drape predict` shows).
    int random_start_seeds = 2;
    /// The preset also draped from flat (the first of the random-start seeds, for
    /// every record) on this finer grid, reported as `cold_fine_*`: whether the preset
    /// carries over to a CAD's finer mesh. 0 = off (the library's
    /// default; `drape fit` checks at 61 unless --flat-grid).
    int flat_check_grid = 0;
    /// The preset as a CAD drapes it: when the preset's drapes from flat (the
    /// `cold_*` seeds on the fit's grid and the `cold_fine_*` one) lay the record's
    /// fold count within 1 but miss its D by more than the D channel's sigma, both
    /// bendings are scaled by one factor (their ratio kept) so that those drapes give
    /// the record's D: one step on the exact sensitivity of D at the optimum, a
    /// secant step if the first did not get within the sigma, each verified by the
    /// same drapes from flat and kept only if those drapes are closer to the record
    /// ((D error / its sigma)^2 + (fold error / 0.75)^2) with the fold count within 1.
    /// Records fitted from the random mix (no fold branch) are left out. Off in the library (the synthetic tests' truth needs no
    /// calibration); `drape fit` turns it on unless --flat-calibration off.
    bool flat_calibration = false;
    NoiseModel noise;
    /// Channels in the objective (dc, nodes, hem, contours); the others are
    /// held out: computed, reported and analysed as predictions, not fitted.
    std::vector<std::string> channels = {"dc", "nodes", "hem", "contours"};
    cloth::RestOptions rest;      ///< solver options of each simulation (progress/cancel are set by the fit)
    /// Newton iterations of a warm re-solve (from the best point's rest states,
    /// Start::Best) before it counts as not at rest; cold drapes keep
    /// rest.max_newton. A drape not at rest is never the fit's best point
    /// (Evaluator::objective), so past this the solve only decides how long the
    /// fit waits for a step it will reject. On the set-a fits (2026-12-01) the 145
    /// warm re-solves that came to rest took at most 329 iterations (median 23,
    /// 99th percentile 266); the one that did not ran to the 1,000 cap (10.9 s).
    long warm_max_newton = 500;
    /// Start point / values of the parameters not fitted (e.g. a library preset:
    /// the local stage also starts from it). Areal density and thickness always
    /// come from the records.
    std::optional<cloth::FabricParams> start;
    std::function<void(const FitProgress&)> progress;
    const std::atomic<bool>* cancel = nullptr;
    int parallel_seeds = 2;       ///< simulations run concurrently (threads)
    /// Measurement-model component "profiler axis": re-centre the contour stacks
    /// of records and simulations on their own axis (MeasuredDrape::recentre_contours).
    bool recentre_contours = false;
    /// Measurement-model component "profiler axis tilted": remove each contour
    /// stack's axis line, offset + depth x tilt (MeasuredDrape::untilt_contours).
    bool untilt_contours = false;
    /// Engine options of every simulation. edge_contact = false reproduces the
    /// vertex-only contact of the seed (and of Drapekit before edge contact), whose
    /// coarse elements cut the pedestal rim. The library's default is the
    /// engine's (plain bending stencils, what the unit tests' synthetic records
    /// and the blind suite at grid 25 are made with); `drape fit`, bench_fit and
    /// the demo set bending_correction (docs/decisions/0011-bending-correction.md).
    cloth::ModelOptions model_options;
};

/// Estimate of one parameter of the table.
struct ParamEstimate {
    cloth::Param id{};
    std::string key;
    std::string unit;
    std::string role;       ///< "fitted" | "held" (ShearHold) | "declared" (by the lab) | "fixed" (default) | "not identifiable"
    double value = 0;       ///< [unit]
    double lower95 = 0, upper95 = 0; ///< 95 % interval (fitted only) [unit]
    double sigma_coord = 0; ///< 1-sigma in search coordinates (decades for log parameters)
    bool constrained = true;///< false: the interval spans more than a decade, hits a bound, or the data has no say
    std::string note;
};

/// Per-record comparison at the optimum.
struct RecordFit {
    MeasuredDrape measured;
    DrapeFeatures measured_features;
    DrapeFeatures simulated_features; ///< seed-averaged
    std::vector<cloth::DrapeResult> simulations; ///< one per seed, at the optimum
    cloth::DrapeSetup setup;          ///< of the first seed
    int branch_folds = 0;             ///< fold count the cold drapes started with (FoldBranch::Measured); 0 = random mix
    double dc_error_percent = 0;      ///< simulated - measured D
    double node_error = 0;            ///< simulated (seed mean) - measured
    /// The preset draped from flat with the random mix of modes, as `drape
    /// predict` / `compare` and the widget drape it (FitOptions::random_start_seeds,
    /// or the spread stage's seeds when the fit starts from the random mix): the
    /// fit's own drapes start on the measured branch or warm and can hold another
    /// fold count. 0 seeds = not run.
    int cold_seeds = 0;
    DrapeFeatures cold_features;
    double cold_dc_error_percent = 0;
    double cold_node_error = 0;
    /// The same preset from flat (first seed) on FitOptions::flat_check_grid; 0 = not run.
    int cold_fine_grid = 0;
    bool cold_fine_converged = false; ///< that drape came to rest (else its numbers describe a state it does not rest in)
    DrapeFeatures cold_fine_features;
    double cold_fine_dc_error_percent = 0;
    double cold_fine_node_error = 0;
    /// Exact sensitivity of the first seed's drape coefficient at the optimum to
    /// each fitted parameter: D change [points] for +10 % of the parameter (dx/dp =
    /// H^-1 df/dp at its rest state, cloth/rest_sensitivity.hpp). Empty when the
    /// rest state was not converged or the fit was cancelled.
    std::vector<std::pair<cloth::Param, double>> d_drape_per_10_percent;
    /// The preset as saved, draped as the fit drapes (on the fit's branch, warm
    /// from the optimum's rest states, the fit's seeds): when the flat calibration
    /// moved it off the contours' optimum, its own drapes (preset_moved); else the
    /// optimum's (simulated_features). What a user who drapes the saved preset on
    /// the record's fold branch gets, beside the optimum's "as fitted" row.
    bool preset_moved = false;
    bool preset_converged = true; ///< every one of those drapes came to rest
    DrapeFeatures preset_features;
    double preset_dc_error_percent = 0;
    double preset_node_error = 0;
    /// The free-strip bound (cloth/elastica.hpp): the bending whose free radial
    /// strips drape to the record's D (NaN: no D, or no declared weight), and the
    /// D the preset's own strips drape to at the record's set-up (the mean of a
    /// warp and a weft strip). A drape lies at or above its strips, so when the
    /// preset's strips are more than kFreeStripMarginPoints above the record's D
    /// no drape of the preset's bending can reach it (`below_free_strips`).
    double free_strip_bound_Nm = std::numeric_limits<double>::quiet_NaN();
    double free_strip_preset_dc_percent = std::numeric_limits<double>::quiet_NaN();
    bool below_free_strips = false;
};

/// How far [points of D] a preset's free strips may lie above a record's D before
/// the record is reported as out of the preset's reach: about twice a drapemeter's
/// repeatability (0.3-0.4 points) and the discretisation of the strips.
inline constexpr double kFreeStripMarginPoints = 1.0;

/// One evaluation of the fit (the convergence trace of the report).
struct FitTraceEntry {
    int evaluation = 0;
    std::string stage;
    double chi2 = 0;      ///< of this evaluation (fitted terms)
    double best_chi2 = 0; ///< best so far
    std::vector<double> coords; ///< search coordinates (log10 for log-scaled parameters)
    double elapsed_s = 0;
};

/// The work a fit, one of its runs or one of its stages did. Runs add up (+); what
/// a stage did is the difference of the evaluator's counts after and before it (-).
struct WorkCounters {
    int evaluations = 0;
    long simulations = 0;
    long factorisations = 0;      ///< Hessians factorised for sensitivities (one per drape linearised)
    long back_substitutions = 0;  ///< sensitivity solves (one per parameter per factorisation)
    /// Jacobian entries left at 0 because their feature jumped between the
    /// difference's points (slopes at the step and at half of it disagree:
    /// a selection that switched - an outermost crossing, a closing cut).
    long jacobian_jumps = 0;
    int jacobians = 0;            ///< Jacobians taken (scan slopes, Levenberg-Marquardt steps, intervals, effect tests)
    double simulation_seconds = 0; ///< summed over the simulations (each thread's counted)
    double wall_seconds = 0;
    double seconds_per_simulation() const { return simulations ? simulation_seconds / simulations : 0.0; }
    WorkCounters& operator+=(const WorkCounters& o)
    {
        evaluations += o.evaluations;
        simulations += o.simulations;
        factorisations += o.factorisations;
        back_substitutions += o.back_substitutions;
        jacobian_jumps += o.jacobian_jumps;
        jacobians += o.jacobians;
        simulation_seconds += o.simulation_seconds;
        wall_seconds += o.wall_seconds;
        return *this;
    }
    WorkCounters& operator-=(const WorkCounters& o)
    {
        evaluations -= o.evaluations;
        simulations -= o.simulations;
        factorisations -= o.factorisations;
        back_substitutions -= o.back_substitutions;
        jacobian_jumps -= o.jacobian_jumps;
        jacobians -= o.jacobians;
        simulation_seconds -= o.simulation_seconds;
        wall_seconds -= o.wall_seconds;
        return *this;
    }
    friend WorkCounters operator+(WorkCounters a, const WorkCounters& b) { return a += b; }
    friend WorkCounters operator-(WorkCounters a, const WorkCounters& b) { return a -= b; }
};

/// A fit's result; its work (WorkCounters) is the whole fit's, every run's added.
struct FitResult : WorkCounters {
    std::string name;                           ///< the preset's name (empty: the first record's id)
    std::string blas_kernel;                    ///< the BLAS kernels its drapes rounded with (cloth::blas_kernel)
    cloth::FabricParams params;                 ///< best fit (areal density/thickness of the first record)
    std::vector<FitVariable> variables;
    Eigen::VectorXd best_coords;                ///< search coordinates of the optimum
    std::vector<ParamEstimate> estimates;       ///< one per parameter of the table
    Eigen::MatrixXd covariance;                 ///< of the search coordinates
    Eigen::MatrixXd correlation;
    std::vector<ResidualTerm> residuals;        ///< at the optimum
    double chi2 = 0;
    int dof = 0;
    ResidualAnalysis residual;
    std::vector<RecordFit> records;
    std::vector<FitTraceEntry> trace; ///< every evaluation, in order (a refit's follow the coarse fit's)
    bool cancelled = false;
    /// A fitted bending's bending length is below the fit's mesh spacing: the
    /// preset is tied to the fit's grid (predictions keep the mesh density).
    bool grid_bound = false;
    /// What FitOptions::refine_grid did (from_grid = 0: no refit was tried).
    struct Refinement {
        int from_grid = 0, to_grid = 0;
        bool adopted = false;       ///< this result is the refit; else it is the grid-bound coarse fit
        double coarse_chi2 = 0, fine_chi2 = 0;
        int coarse_dof = 0, fine_dof = 0;
        std::string reason;         ///< one sentence: why the refit was or was not adopted
    } refinement;
    /// Warp/weft bending (BendingTie): the free fit's ratio, whether its interval
    /// separates it from 1, and the tied refit when one was made.
    struct Anisotropy {
        bool assessed = false;      ///< both bendings were fitted apart and have an interval
        double ratio = 1;           ///< B warp / B weft of the free fit
        double ratio_lower95 = 0, ratio_upper95 = 0; ///< its 95 % interval (from the covariance of the log10 coordinates)
        bool separated = false;     ///< the interval excludes 1
        /// Set-ups whose records alone (one Gauss-Newton step from the joint
        /// optimum on their rows and the priors', linearised) put the ratio on the
        /// same side of 1 as the joint fit at 95 %. A ratio beyond the typical
        /// factor is kept only when two set-ups confirm it (docs/decisions/0029).
        int setups_confirming = 0;
        int setups = 0;             ///< set-ups among the records
        bool refit = false;         ///< a tied fit was made
        bool tied = false;          ///< this result is the tied fit (one bending for warp and weft)
        double free_chi2 = 0, tied_chi2 = 0;
        int free_dof = 0, tied_dof = 0;
        double delta_chi2 = 0;      ///< (tied - free) / max(1, free chi2 / dof)
        std::string reason;         ///< one sentence for the report
    } anisotropy;
    /// In-plane shear (ShearHold): whether the data constrain it, and the held
    /// refit when it was tried.
    struct ShearHeld {
        bool assessed = false;      ///< the shear was fitted and had an interval before the hold
        double fitted_N_m = 0;      ///< the fitted value
        double lower95_N_m = 0, upper95_N_m = 0; ///< its 95 % interval (the Jacobian at that optimum, before the spread calibration)
        bool at_bound = false;      ///< the fitted value was at a fit bound (then not constrained, whatever the interval)
        bool constrained = false;   ///< the interval lies inside the fit bounds (however wide): fitted, not held
        bool tried = false;         ///< the held refit was made
        bool held = false;          ///< this result's shear is held at held_N_m
        double held_N_m = 0;
        double fitted_chi2 = 0, held_chi2 = 0; ///< before the spread calibration (the search's sigmas)
        double delta_chi2 = 0;      ///< (held - fitted) / max(1, fitted chi2 / dof)
        std::string reason;         ///< one sentence for the report
    } shear_hold;
    /// FitOptions::priors: what each prior row did at the optimum. The data's own
    /// sigma of the prior's combination (log10 of warp / weft, or of the mean
    /// bending) from the Jacobian of the records' rows alone; where it is wider than
    /// the prior's, the prior, not the data, decided that combination.
    struct PriorUse {
        std::string kind;          ///< "prior_anisotropy" | "prior_bending"
        double value = 0;          ///< the combination at the optimum [decades: log10 of the ratio, or of N*m]
        double centre = 0;         ///< the prior's centre
        double prior_sigma = 0;    ///< [decades]
        double data_sigma = 0;     ///< the records' alone [decades]; infinity: they do not see it
        bool decided_by_prior = false;
    };
    std::vector<PriorUse> priors;
    /// FitOptions::flat_calibration: the preset moved so that, draped from flat, it
    /// gives the record's D - the bendings rescaled - or, where its fold count was
    /// more than 1 off, the record's fold count within 1 - a step along the contours'
    /// profile, where the other fitted parameters follow the bendings (the contour
    /// fit's optimum is the search's; `params` and the moved estimates are the
    /// calibrated preset's).
    struct FlatCalibration {
        bool tried = false;         ///< the stage ran (drapes from flat available)
        bool applied = false;       ///< the preset was moved (its bendings, and with fold_search the other fitted parameters)
        double scale = 1;           ///< factor on both bendings (1: not applied; the other moved parameters: the estimates' notes)
        double error_before = 0;    ///< mean D from flat - measured D over the records, at the contour optimum [points]
        double error_after = 0;     ///< the same at the calibrated preset (= before when not applied)
        double tolerance = 0;       ///< the D channel's sigma: errors within it are left alone [points]
        double bend_warp_fitted = 0, bend_weft_fitted = 0; ///< the contour optimum's bendings [N*m]
        double chi2_increase = 0;   ///< linearised chi2 increase of the fitted terms for the scale (Jacobian at the optimum; NaN: not taken)
        double chi2_preset = std::numeric_limits<double>::quiet_NaN();    ///< the fitted terms' chi2 at the calibrated preset, draped as the fit drapes (applied only; NaN: not drawn)
        int steps = 0;              ///< calibration steps drawn (each: the drapes from flat again, or only the fit grid's)
        double fold_error_before = 0, fold_error_after = 0; ///< worst fold-count error of a drape from flat, at the optimum / the preset
        bool fold_search = false;   ///< the fold count was off by more than 1: steps along the contours' profile were tried
        bool fold_search_failed = false; ///< none of them laid it within 1 (not calibrated)
        double fold_direction = 0;  ///< -1: softer bendings (too few folds), +1 stiffer, 0: no profile (no Jacobian)
        double fold_sigmas = 0;     ///< the kept step's size in sigmas of the profile (1 or 2, less where the box shortened it; 0: none kept)
        struct Moved {
            std::string key;         ///< parameter table key
            double before = 0, after = 0; ///< the contours' optimum's value and the preset's
        };
        std::vector<Moved> moved;   ///< every parameter the calibration moved (applied only)
        struct Step {
            double scale = 1, error = 0, fold_error = 0; ///< the bendings' factor, the mean D error from flat [points], worst fold-count error
            std::string kind = "D";  ///< "fold count": a step along the contours' profile; "D": a bending scale
            double sigmas = 0;       ///< a profile step's size in its sigmas (0 for the others)
            double chi2_cost = 0;    ///< linearised chi2 increase of the fitted terms (NaN: no Jacobian)
            bool finer_grid = true;  ///< the flat_check_grid drape was drawn too (not for the fold search's screening steps, nor when that grid is off)
        };
        std::vector<Step> history;  ///< every step drawn, in order
        std::string reason;         ///< one sentence for the report
    } flat_calibration;
    FitOptions options;
};

} // namespace drape::estimate
