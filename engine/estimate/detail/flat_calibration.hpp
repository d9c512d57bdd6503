#pragma once
// One flat calibration of a kept result (calibrate_from_flat, pipeline.hpp;
// docs/decisions/0020-flat-calibration.md): what the optimum's drapes from flat
// say, the measures its steps share, and the best drapes drawn so far. The D
// scale, the preset's move and its drapes as saved are fit_calibration.cpp; the
// fold count's step along the contours' profile is fit_calibration_folds.cpp.
// Internal to the estimate layer.
#include "engine/estimate/detail/evaluator.hpp"

#include <string>
#include <vector>

namespace drape::estimate::detail {

struct FlatCalibrator {
    /// Resets kept.flat_calibration and notes the optimum's bendings.
    FlatCalibrator(Evaluator& ev, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x, const Eigen::MatrixXd& J_opt,
                   FitResult& kept);

    Evaluator& ev;
    const std::vector<FitVariable>& vars;
    const Eigen::VectorXd& x;     ///< the contours' optimum
    const Eigen::MatrixXd& J_opt; ///< the whitened Jacobian there (another size: none)
    FitResult& kept;
    FitResult::FlatCalibration& c;
    std::size_t R = 0; ///< records

    // The optimum's drapes from flat (needs_calibration, bendings_scalable).
    double e0 = 0, folds0 = 0, signed0 = 0; ///< mean D error, worst and mean signed fold-count error
    std::vector<char> used;                 ///< the records that took part
    int n_used = 0;
    std::string over;          ///< " (mean over n records)" for the reasons
    std::vector<int> bend;     ///< the bending coordinates
    std::string miss;          ///< what the optimum's drapes miss, for the reasons
    // The measures the steps share (prepare_steps).
    double node_sigma = 0.75;  ///< the node channel's sigma
    double ratio0 = 1;         ///< the optimum's warp/weft bending ratio
    bool have_J = false;       ///< a Jacobian at the optimum to linearise the contours with
    double s2 = 1;             ///< max(1, chi2 / dof): a fit worse than its noise widens the profile, as the intervals
    double slope = 0;          ///< dD / d ln(scale of both bendings) at the optimum, over the records used
    bool slope_ok = false;     ///< that slope is known and positive
    double max_step = 0;       ///< the largest ln(scale) of one step
    bool finer = false;        ///< the drapes from flat include the finer grid's
    // The best drapes so far (keep).
    double best_score = 0, best_e = 0, best_folds = 0;
    Eigen::VectorXd best_x;
    std::vector<RecordFit> best_records; ///< the kept step's drapes from flat (empty: the optimum's)

    /// The records' mean error from flat (one scale moves them together: its best
    /// is the mean's zero), the worst fold-count error of any drape, the mean signed
    /// fold-count error, and which records took part; returns how many did.
    int measure(double& e, double& folds, std::vector<char>* records_used, double* signed_folds = nullptr) const;
    bool is_bend(int i) const;
    /// How far drapes are from the record: D in the D channel's sigmas, the fold
    /// count in the node channel's (0.75, NoiseModel), squared and summed.
    double score(double e, double folds) const;
    /// The drapes at xs (the evaluator's last) become the best so far.
    void keep(const Eigen::VectorXd& xs, double e, double folds);
    /// Linearised chi2 of the fitted terms at x + dx minus at x (whitened Jacobian at
    /// the optimum); NaN without one (the derivative-free method, --no-uncertainty).
    double lin_cost(const Eigen::VectorXd& dx) const;
    /// Both bendings scaled by exp(ln_s) from `from` (ratio kept); false when the
    /// bounds would clip the step or bend the warp/weft ratio.
    bool scaled(const Eigen::VectorXd& from, double ln_s, Eigen::VectorXd& xs) const;
    /// The bendings' factor at xs against the optimum's.
    double bend_scale(const Eigen::VectorXd& xs) const;

    /// Decides whether the optimum's drapes from flat call for a calibration: false
    /// (the reason says why) when there are none or they lay the record within the D
    /// channel's sigma and the fold count within 1.
    bool needs_calibration();
    /// Decides whether the bendings can move: false (the reason says why) when they
    /// are not fitted, or not on a log scale.
    bool bendings_scalable();
    /// The measures the steps share: the scores, the Jacobian, D's slope, the finer grid.
    void prepare_steps();
    /// Decides the fold count's step along the contours' profile (a fold count more
    /// than 1 off): true when a step was kept; false: the reason says why not.
    /// (fit_calibration_folds.cpp)
    bool step_fold_count();
    /// The contours' profile through the optimum: per decade of the bendings, where
    /// the other fitted coordinates follow (those a bound stops held there).
    struct FoldProfile {
        double sign = 1;           ///< -1: softer bendings (too few folds), +1: stiffer
        Eigen::VectorXd dir;       ///< the coordinates' move per decade of the bendings
        double unit = 0;           ///< the linearised contours' curvature along dir
        double sigma_t = 0;        ///< the profile's sigma [decades of bending]
        std::vector<int> held;     ///< coordinates held at a bound (or the held shear)
        bool shear_held = false;   ///< the shear is held at the typical value
        int limit_var = -1;        ///< the coordinate that shortened the last step (profile_step)
        bool limit_by_cap = false; ///< ... by its cap, not the box
        std::string why_not;       ///< no step along it, and why
    };
    FoldProfile fold_profile() const;
    /// The step of k sigma of the profile, shortened where a coordinate would leave
    /// the box or move more than k decades (k tenths of a linear range).
    double profile_step(FoldProfile& fp, double k) const;
    /// Sets fp.why_not when no other coordinate follows the bendings or the first
    /// step is nothing.
    void check_profile_steps(FoldProfile& fp) const;
    /// "shear_N_m moves 29.7 decades": how fast coordinate i follows the bendings.
    std::string follower_rate(const FoldProfile& fp, int i, const char* verb) const;
    /// The fold count's step found on the fit grid's drapes (`cand`: its point, D
    /// error, score and sigmas of the profile): one bending scale step for D on the
    /// same drapes, then the finer grid's drape; true when kept (keep), false: the
    /// reason says why not. (fit_calibration_folds.cpp)
    bool confirm_fold_step(Eigen::VectorXd cand, double cand_e, double cand_score, double cand_sigmas);
    /// Decides the bending scale for D (the fold count within 1): at most two steps,
    /// each kept when its drapes are closer to the record.
    void scale_for_d();
    /// Decides what goes into the preset: false (the reason says why) when no step was
    /// kept; else the moved parameters, their estimates' notes and the reason.
    bool apply();
    /// The preset as saved, draped as the fit drapes: its preset_* rows and chi2.
    void drape_preset_as_saved();
};

} // namespace drape::estimate::detail
