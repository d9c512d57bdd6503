#pragma once
// Prediction of a preset's drape on a set-up: what `drape predict` prints and
// what the transfer benchmark scores. The preset is draped from flat as its
// fit's lab laid its specimens (FabricPreset::laid), on the fit's mesh density
// (the fit's grid scaled with the specimen's diameter), with several
// perturbation seeds; the drape coefficient and the fold count come with a
// 95 % interval built from
//   - the fit's covariance of its fitted coordinates, pushed through the exact
//     sensitivity of D at the predicted rest state (cloth/rest_sensitivity.hpp),
//   - the spread of the drapes over the starts (the fold-pattern bifurcation),
//   - the drape-to-drape variation of real repeats of one specimen
//     (kRepeatSigmaPercent), which a single record cannot show.
#include "engine/cloth/drape.hpp"
#include "engine/fabric/preset.hpp"

#include <Eigen/Core>

#include <atomic>
#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace drape::estimate {

/// Standard deviation of D between real repeats of one specimen draped again
/// [points]: Cusick drapes of woven fabrics repeated on one specimen spread by
/// 1.5-9.3 points (range over the repeats; Gong, Mao, Wang 2024, CVPR, five of
/// their 25 fabrics), about 2.5 points as a standard deviation for their
/// median spread of ~5 points over four repeats (the range of four normal
/// draws is about 2 sigma). docs/decisions/0028-prediction-intervals.md.
inline constexpr double kRepeatSigmaPercent = 2.5;

/// Folds a real repeat may lay more or fewer than the drapes drawn here: a
/// drape test's fold count changes "a fold now and then" between repeats
/// (the lab's README; Cusick 1968).
inline constexpr int kRepeatFolds = 1;

/// The model's error in the change of D between set-ups, as a fraction of the
/// change it predicts: a preset fitted at one set-up and predicted at another
/// carries sigma = kTransferFraction x |D predicted - D of the nearest fitted
/// record| on top of the other terms (0 on a fitted set-up). The RMS of (error /
/// predicted change) over the 27 held-out predictions of the drape lab's set-d
/// (its three fabrics, each set-up left out of single and pair fits;
/// bench_transfer); estimated from two fabrics, it covered 25 of the third's 27
/// (docs/decisions/0028-prediction-intervals.md). A model error, so a better
/// model lowers it: re-estimate with bench_transfer when the model changes.
inline constexpr double kTransferFraction = 0.47;

/// The grid a fitted preset was fitted at, scaled to a specimen of
/// `sample_diameter` [m] (provenance.grid at the fit's first record's diameter,
/// fit.sample_diameter_m, else 300 mm): the same mesh density. Odd (the centre
/// a node) and within [9, 201]. None when the preset has no fit grid.
std::optional<int> fit_grid_for(const fabric::FabricPreset& preset, double sample_diameter);

/// The set-up a preset is predicted on by default: `s` laid as the preset's lab
/// laid its specimens, on the fit's mesh and (when `s.grid` is 0) its grid
/// scaled to s.sample_diameter (31 for a preset without a fit grid).
cloth::DrapeSetup prediction_setup(const fabric::FabricPreset& preset, cloth::DrapeSetup s);

struct PredictOptions {
    /// Perturbation seeds draped from flat: setup.seed, setup.seed + 1, ... The
    /// point prediction is their mean D and median fold count.
    int seeds = 3;
    /// Build the intervals (the sensitivity of D at the first drape's rest state
    /// and the preset's covariance); false: the drapes only.
    bool intervals = true;
    /// The drape-to-drape term of the interval [points of D].
    double repeat_sigma_percent = kRepeatSigmaPercent;
    int repeat_folds = kRepeatFolds;
    /// The transfer term's fraction (kTransferFraction; 0: none).
    double transfer_fraction = kTransferFraction;
    cloth::RestOptions rest;
    /// Called before each drape with its index and the count.
    std::function<void(int, int)> on_drape;
    const std::atomic<bool>* cancel = nullptr;
};

struct Prediction {
    cloth::DrapeSetup setup;                  ///< the first drape's (seed = setup.seed)
    std::vector<cloth::DrapeResult> drapes;   ///< one per seed, in order
    bool converged = true;                    ///< every drape came to rest
    double dc_percent = 0;                    ///< mean D over the drapes [%]
    int node_count = 0;                       ///< median fold count of the drapes
    int node_min = 0, node_max = 0;           ///< the fold counts the drapes laid
    /// 95 % interval of the D a real test of the fabric on this set-up reads
    /// (NaN when no interval was built) [%].
    double dc_lower95 = 0, dc_upper95 = 0;
    int nodes_lower = 0, nodes_upper = 0;     ///< the fold counts a real test may lay
    /// The interval's terms (1 sigma, points of D): the fit's parameters, the
    /// spread over the starts, the drape-to-drape term.
    double sigma_parameters_percent = 0, sigma_starts_percent = 0, sigma_repeat_percent = 0;
    /// The transfer term [points]: kTransferFraction x |transfer_change_percent|,
    /// 0 when the set-up is one the preset was fitted on (or it has no records).
    double sigma_transfer_percent = 0;
    /// The fitted record nearest to the set-up (by overhang and disc-to-specimen
    /// ratio; empty: none in the preset) and the change of D the prediction makes
    /// from its measured D [points].
    std::string transfer_from;
    bool fitted_setup = false;             ///< the set-up is one of the fitted records'
    double transfer_change_percent = 0;
    bool parameters_known = false;            ///< the preset carries its fit's covariance (else sigma_parameters is 0)
    std::vector<std::string> parameter_keys;  ///< the fitted coordinates the parameter term covers
    std::vector<double> d_dc_per_coordinate;  ///< dD/d(search coordinate) [points per decade, or per unit]
    double wall_seconds = 0;
};

/// The covariance of a fitted preset's search coordinates (log10 of a log
/// parameter, else its value), rebuilt from fit.parameters[].sigma_search_coordinate
/// and fit.correlation; `keys` names its rows (parameter-table keys; a tied
/// bending is "bend_Nm"). Empty when the preset has no fit or no intervals.
Eigen::MatrixXd fit_covariance(const fabric::FabricPreset& preset, std::vector<std::string>& keys);

/// Drapes `preset` on `setup` (as prediction_setup makes it) from flat with
/// options.seeds seeds and builds the intervals. Throws ParameterError for a
/// bad set-up; a drape that does not come to rest sets converged = false.
Prediction predict_drape(const fabric::FabricPreset& preset, const cloth::DrapeSetup& setup, const PredictOptions& options = {});

} // namespace drape::estimate
