#pragma once
// The fit's evaluator: runs the simulations of one parameter point (every
// record times every perturbation seed, from flat or warm from the best point's
// rest states), turns them into whitened residuals, keeps the best point, and
// measures the drape-to-drape spread of every residual term. Internal to the
// estimate layer (fit.cpp and its stage files fit_*.cpp, stages.cpp, uncertainty.cpp).
#include "engine/cloth/drape.hpp"
#include "engine/estimate/effects.hpp"
#include "engine/estimate/fit_types.hpp"

#include <chrono>
#include <cmath>
#include <string>
#include <vector>

namespace drape::estimate::detail {

using Clock = std::chrono::steady_clock;

struct Evaluation {
    double chi2 = HUGE_VAL;
    std::vector<ResidualTerm> terms;
    std::vector<DrapeFeatures> features;               ///< seed-averaged, per record
    std::vector<std::vector<cloth::DrapeResult>> sims; ///< [record][seed]
    /// There are drapes and every one came to rest (false before any drape:
    /// no best point yet).
    bool at_rest() const
    {
        if (sims.empty()) return false;
        for (const auto& rs : sims)
            for (const auto& s : rs)
                if (!s.status.converged()) return false;
        return true;
    }
};

/// Whether a Jacobian entry's two central differences - over the step d (`full`)
/// and over d / 2 (`half`), whitened per search coordinate - describe one slope.
/// A smooth feature's differ by O(d^2) and by the metrics' own discretisation (at
/// the set-a optima at most 0.008 per decade); a feature that jumps by J between
/// the points reads J / (2 d) at one step and J / d or nothing at the other (a
/// 1 mm jump of a 2 mm sigma at d = 1e-3 decades: hundreds). Agree: within 10 %
/// of the larger and `floor` (Evaluator::jacobian: 0.05 sigma per thousand steps -
/// a decade of a log coordinate, the range of a linear one). A kink between the
/// points reads as two slopes too.
bool slopes_agree(double full, double half, double floor);

/// Thrown out of an evaluation when FitOptions::cancel is set.
struct CancelledFit {};

/// Where each simulation starts: flat and perturbed by its seed (Cold), or
/// from its seed's rest state at the best point so far (Best). Warm starts keep
/// each seed's fold pattern unless the parameters make it unstable.
enum class Start { Cold, Best };

class Evaluator {
public:
    Evaluator(const std::vector<MeasuredDrape>& recs, const FitOptions& opt, std::vector<FitVariable> vars,
              cloth::FabricParams base);

    /// Set-up of record r's simulation with perturbation seed `seed`: on the
    /// record's measured fold branch (FitOptions::branch) or from the random mix.
    cloth::DrapeSetup setup_for(int r, std::uint64_t seed, bool on_branch) const;
    /// The fold count record r's cold drapes start with (0: random mix).
    int branch_of(int r) const;
    /// The full parameter set at search coordinates x (clamped to the table's bounds).
    cloth::FabricParams params_at(const Eigen::VectorXd& x) const;

    /// Simulates every record and seed at x and scores the result. Throws CancelledFit.
    Evaluation evaluate(const Eigen::VectorXd& x, Start from);
    /// Measures the drape-to-drape spread of every residual term at `x` with
    /// `extra` more perturbation seeds (cold starts), and raises each term's
    /// sigma to that spread where the default floor was optimistic (the spread
    /// depends on the fabric and the grid: 0.6 mm for the cos 2theta term of an
    /// isotropic fabric at grid 25, several mm with 4-5 folds at grid 17).
    /// Where the fit's branch is the random mix, the spread's drapes are the
    /// report's cold_* ones; elsewhere draw_from_flat draws those later, for the
    /// run that is kept. Re-scores the best point with the new sigmas. The drapes
    /// run on parallel_seeds threads; with FitOptions::term_sigmas given (which
    /// replace the calibrated ones) only the cold_* drapes are drawn.
    void calibrate_spread(const Eigen::VectorXd& x, int extra);
    /// The cold_* drapes calibrate_spread leaves out: per record on another
    /// branch than the random mix, random_start_seeds drapes from it, and the
    /// flat_check_grid one. `which`: FitGrid draws only the fit grid's drapes (and
    /// drops the finer grid's, which were another point's): a caller screens a
    /// candidate on the cheap drapes before it pays for the finer one. Drapes
    /// drawn at the same parameters before (the last kFlatMemoPoints points) are
    /// not drawn again, and the finer grid's drape starts from the coarse level
    /// its seed's fit-grid drape passed (cloth::LevelRest): the same drapes,
    /// fewer simulations.
    /// The drapes are announced and reported as `stage` (FitOptions::progress, the trace).
    enum class FlatDraw { All, FitGrid };
    void draw_from_flat(const Eigen::VectorXd& x, Stage stage, FlatDraw which = FlatDraw::All);
    /// Parameter points whose drapes from flat draw_from_flat keeps.
    static constexpr std::size_t kFlatMemoPoints = 6;
    /// Finer drapes from flat that started from a kept continuation level.
    long flat_levels_reused() const { return m_flat_levels_reused; }
    /// Objective for the optimizers: evaluates, keeps the best point and its rest
    /// states. An evaluation with a drape not at rest never replaces a best point
    /// at rest, and returns no less than the best chi2 then (the optimizers do not
    /// centre on it).
    double objective(const Eigen::VectorXd& x, Start from, Stage stage);
    /// objective() with every drape re-solved from `states` ([record][seed], on
    /// this evaluator's grid and seeds: a tied refit continues the free fit's
    /// drapes) instead of the best point's; they stay the warm starts only if the
    /// evaluation becomes the best point. Throws ParameterError when the layout
    /// does not match the records and seeds.
    double objective_from(const Eigen::VectorXd& x, const std::vector<std::vector<cloth::Positions>>& states, Stage stage);
    /// Calls FitOptions::progress with the state so far.
    /// Also appends the evaluation to the trace (once per evaluation).
    void report(Stage stage);
    /// Calls FitOptions::progress for a stage that starts now (FitProgress::starting),
    /// without touching the trace: the drapes after the search take seconds each.
    void announce(Stage stage);

    /// Jacobian of the whitened residual terms of `e` (the evaluation at x, whose
    /// rest states it linearises) with respect to the search coordinates: rows in
    /// the order of e.terms, one column per variable. Columns come from the exact
    /// rest-state sensitivities (dx/dp = H^-1 df/dp, one factorisation per drape,
    /// one back-substitution per parameter) pushed through the shared metric code
    /// along x +- d dx/dc; a variable they cannot serve (its value is 0, where it
    /// switches an effect on, or a drape not at rest) gets a one-sided difference
    /// of warm re-solves. Rows of terms that are not smooth (the node count) or
    /// not fitted are zero. `resolves` = false: no re-solves; the columns the
    /// sensitivities cannot serve stay zero. Throws CancelledFit.
    Eigen::MatrixXd jacobian(const Eigen::VectorXd& x, const Evaluation& e, bool resolves = true);
    const std::vector<FitTraceEntry>& trace() const { return m_trace; }
    /// Signatures of the candidate effects (effects.hpp) at the evaluation `e`
    /// at x: rows as e.terms (whitened with their sigmas; zero for terms not
    /// fitted or not smooth). Parameter effects from the rest-state
    /// sensitivities, switches from warm re-solves (counted as simulations),
    /// instrument effects from re-measured positions. Throws CancelledFit.
    std::vector<EffectSignature> effect_signatures(const Eigen::VectorXd& x, const Evaluation& e);
    /// The evaluation at full parameters p (not a search point; not the best).
    Evaluation evaluate_params(const cloth::FabricParams& p, Start from);
    long factorisations() const { return m_work.factorisations; }
    int jacobians() const { return m_work.jacobians; }
    long back_substitutions() const { return m_work.back_substitutions; }
    /// Jacobian entries left at 0 because the feature jumped between the
    /// difference's points (its slopes at the step and at half of it disagree).
    long jacobian_jumps() const { return m_work.jacobian_jumps; }

    const Evaluation& last() const { return m_last; }
    const Eigen::VectorXd& last_x() const { return m_last_x; }
    const std::vector<DrapeFeatures>& measured() const { return m_meas; }
    const Evaluation& best() const { return m_best; }
    const Eigen::VectorXd& best_x() const { return m_best_x; }
    /// Makes e (an evaluation at x, at rest) the best point whatever its chi2, its
    /// rest states the warm starts: a search that goes on under a constraint (a
    /// held coordinate) starts there, and returning to an earlier best point
    /// restores it exactly.
    void set_best(const Evaluation& e, const Eigen::VectorXd& x);
    bool spread_calibrated() const { return m_spread_calibrated; }
    long simulations() const { return m_work.simulations; }
    int evaluations() const { return m_work.evaluations; }
    double sim_seconds() const { return m_work.simulation_seconds; }
    /// Its counts so far (wall_seconds: since it was made); a stage's work is the
    /// difference of two of them.
    WorkCounters work() const;
    /// Wall time since the evaluator was made [s] (the progress's and trace's clock).
    double elapsed_s() const;
    long unconverged() const { return m_unconverged; }
    const std::vector<DrapeFeatures>& cold_features() const { return m_cold; }
    int cold_seeds(std::size_t r) const { return r < m_cold_seeds.size() ? m_cold_seeds[r] : 0; }
    /// Record r's fold count of each drape behind cold_features (the mean hides a
    /// pair 6 and 8 as 7); empty when none.
    const std::vector<double>& cold_node_counts(std::size_t r) const
    {
        static const std::vector<double> none;
        return r < m_cold_nodes.size() ? m_cold_nodes[r] : none;
    }
    const FitOptions& options() const { return m_opt; }
    /// A drape from flat on FitOptions::flat_check_grid, measured.
    struct FineDrape {
        DrapeFeatures features;
        bool at_rest = false;
    };
    /// Record r's drape from flat on FitOptions::flat_check_grid (draw_from_flat); nullptr = not drawn.
    const FineDrape* cold_fine(std::size_t r) const { return r < m_cold_fine.size() && m_cold_fine[r] ? &*m_cold_fine[r] : nullptr; }
    void set_planned(int n) { m_planned = n; }

    /// Rows of the records' residual terms; the prior rows (FitOptions::priors)
    /// follow them, to the end of an evaluation's terms.
    std::size_t record_rows() const { return m_first_term.back(); }
    /// Record r's residual rows: [first_row(r), first_row(r + 1)).
    std::size_t first_row(std::size_t r) const { return m_first_term[r]; }
    /// The prior rows at parameters p (empty without FitOptions::priors or without
    /// a fitted bending): "prior_anisotropy" (log10 of warp / weft; 0 for a tied
    /// bending, so a tied and a free fit have the same rows) and "prior_bending"
    /// (log10 of their geometric mean), record -1, channel "prior".
    std::vector<ResidualTerm> prior_terms(const cloth::FabricParams& p) const;
    /// d(prior row k) / d(search coordinate i), unwhitened (the rows are linear in
    /// the log10 coordinates).
    double prior_slope(const std::string& kind, std::size_t i) const;

private:
    // The linearisation (evaluator_linearise.cpp).
    /// Features per record, seed and column: [r][s][column].
    using FeatureTable = std::vector<std::vector<std::vector<DrapeFeatures>>>;
    /// Record r's residual terms of the seeds' features in `column`, averaged over
    /// the seeds; each depth's fraction of seeds whose slice closed in `closed`.
    std::vector<ResidualTerm> seed_terms(int r, const FeatureTable& feats, std::size_t column, std::vector<double>& closed) const;
    /// A linear coordinate at its lower bound of 0, where it switches an effect on.
    bool at_switch(const Eigen::VectorXd& x, int i) const;
    /// The coordinate step of column i's central difference along dx/dc.
    double column_step(int i) const;
    /// The columns the exact sensitivities serve.
    std::vector<char> exact_columns(const Eigen::VectorXd& x, const cloth::FabricParams& p, const Evaluation& e) const;
    /// The features along each exact column's dx/dc at +-step and +-step/2 (column
    /// 4 i + 0..3); false when there is none or a rest state is not stable.
    bool sensitivity_features(const cloth::FabricParams& p, const Evaluation& e, const std::vector<char>& exact, FeatureTable& feats);
    /// Column i of J from those features, rows whose two slopes disagree left at 0.
    void exact_column(int i, const Evaluation& e, const FeatureTable& feats, Eigen::MatrixXd& J);
    /// Column i of J by a one-sided difference of warm re-solves.
    void resolved_column(int i, const Eigen::VectorXd& x, const Evaluation& e, Eigen::MatrixXd& J);
    /// The candidate effects that can be linearised here (out: every effect of the
    /// library, why_not for the others); returns the parameters whose
    /// sensitivities their signatures need.
    std::vector<cloth::Param> signatures_available(const cloth::FabricParams& p, bool all_at_rest, Eigen::Index rows,
                                                   std::vector<EffectSignature>& out) const;
    /// The features of every record and seed without (`off`, column 0) and with
    /// each available effect (`on[effect]`); effects that could not be made are
    /// marked unavailable in `out`.
    void signature_features(const cloth::FabricParams& p, const Evaluation& e, const std::vector<cloth::Param>& sens_params,
                            std::vector<EffectSignature>& out, FeatureTable& off, std::vector<FeatureTable>& on);
    /// One effect's signature columns from those features, on the rows it reaches.
    void signature_columns(EffectSignature& sig, const Evaluation& e, const FeatureTable& off, const FeatureTable& on) const;

    void progress(Stage stage, bool starting);
    void draw_flat(const Eigen::VectorXd& x, FlatDraw which); ///< draw_from_flat's drapes
    /// One cold drape of record r at p (seed, on the branch or not), measured.
    /// Touches no member (the spread's drapes run on several threads).
    /// grid > 0: on that grid instead of the fit's. at_rest: whether it came to rest.
    /// start, levels: cloth::simulate_drape's (a kept coarse level; the levels passed).
    DrapeFeatures drape_cold(int r, const cloth::FabricParams& p, std::uint64_t seed, bool on_branch, int grid = 0, bool* at_rest = nullptr,
                             const cloth::LevelRest* start = nullptr, std::vector<cloth::LevelRest>* levels = nullptr) const;

    const std::vector<MeasuredDrape>& m_recs;
    const FitOptions& m_opt;
    std::vector<FitVariable> m_vars;
    cloth::FabricParams m_base;
    std::vector<DrapeFeatures> m_meas;
    std::vector<std::size_t> m_first_term; ///< record r's residual terms: [m_first_term[r], m_first_term[r + 1])
    NoiseModel m_noise;
    std::vector<double> m_sigma_floor; ///< per residual term, from calibrate_spread
    bool m_spread_calibrated = false;
    Evaluation m_best, m_last;
    std::vector<DrapeFeatures> m_cold; ///< per record: mean features of the random-start drapes
    std::vector<int> m_cold_seeds;     ///< per record: drapes behind m_cold (0 = none)
    std::vector<std::vector<double>> m_cold_nodes; ///< per record: each of those drapes' fold count
    std::vector<std::optional<FineDrape>> m_cold_fine; ///< per record: from flat on flat_check_grid
    /// A drape from flat draw_from_flat drew (at params `p`), kept for the same point.
    struct FlatMemo {
        cloth::FabricParams p;
        int r = 0;
        std::uint64_t seed = 0;
        int grid = 0; ///< 0: the fit's; or flat_check_grid
        FineDrape drape;
        std::vector<cloth::LevelRest> levels; ///< the continuation's levels it passed
    };
    std::vector<FlatMemo> m_flat_memo; ///< oldest point first
    long m_flat_levels_reused = 0;
    Eigen::VectorXd m_last_x;
    Eigen::VectorXd m_best_x;
    std::vector<std::vector<cloth::Positions>> m_states;
    bool m_have_states = false;
    WorkCounters m_work; ///< its counts (wall_seconds: see work())
    long m_unconverged = 0;
    std::vector<FitTraceEntry> m_trace;
    int m_traced = 0; ///< evaluations already in m_trace
    int m_planned = 0;
    Clock::time_point m_t0;
};

} // namespace drape::estimate::detail
