#pragma once
// Parameter space and objective of the fit: which parameters a drape test can
// constrain, and the whitened residual vector (simulated minus measured, each
// divided by its noise) whose sum of squares the optimizer minimises.
#include "engine/estimate/measured.hpp"

#include "engine/cloth/params.hpp"

#include <string>
#include <vector>

namespace drape::estimate {

/// Model variants selectable with `drape fit --model`.
///  - baseline: the seed paper's model (linear springs, frictionless disc);
///    fits bend_warp, bend_weft and shear.
///  - stiffening: baseline + stiffening bending (bend_stiffening_radius_m).
///  - softening: baseline + yielding bending (bend_softening_radius_m).
///  - full: stiffening + the tensile stiffnesses warp and weft.
///  - buckling: baseline + the membrane's compression limit (buckling_length_m).
///  - peaking: baseline + bending whose moment peaks at a radius and falls beyond
///    (bend_peak_radius_m; real fabrics' cantilever curves, Feng et al. 2022).
/// Disc friction is not fitted: the static solver finds rest states without it
/// (a rest state with friction depends on the path to it).
enum class ModelVariant { Baseline, Stiffening, Softening, Full, Buckling, Peaking, Slack };
ModelVariant parse_model_variant(const std::string& name); ///< "baseline" | "stiffening" | "softening" | "full" | "buckling" | "peaking" | "slack"; ParameterError otherwise
std::string to_string(ModelVariant v);

/// One fitted coordinate: a parameter (or a tied group, e.g. stretch warp and
/// weft together) searched in log10 (or linear) space within the parameter
/// table's fit range (cloth::ParamSpec::fit_lower/fit_upper).
struct FitVariable {
    std::string name;                ///< the parameter's key, e.g. "bend_warp_Nm"
    std::vector<cloth::Param> params;///< set together (tied)
    bool log_scale = true;
    double lower = 0, upper = 0;     ///< fit bounds in search coordinates (log10 of the value when log_scale)
    double to_value(double x) const { return log_scale ? std::pow(10.0, x) : x; }
    double to_coord(double v) const { return log_scale ? std::log10(v) : v; }
};

/// Fitted coordinates of a variant (in the order of the table). `tie_bending`:
/// one coordinate "bend_Nm" sets warp and weft bending together (isotropic).
std::vector<FitVariable> fit_variables(ModelVariant v, bool tie_bending = false);

/// Measurement noise (1 sigma) of each residual channel. The lab's own
/// figures (README): laser 0.3 mm per coordinate, drapemeter 0.5 % D. The
/// "seed" floors are the spread of the drape itself between repeats: the fold
/// pattern is a bifurcation, so one real drape (and one simulation) is one draw.
/// Measured with the engine, perturbation seeds 1..8 at grid 25 on the default
/// fabric (bend 1e-5 N*m, 200 g/m^2; docs/estimate.md): D 34.1..36.9 % (sd 1.0),
/// contour mean radius sd 0.3..0.6 mm, RMS fold amplitude sd 0.5..1.1 mm,
/// signed cos 2theta term sd 0.5..0.7 mm, node count 7..9.
struct NoiseModel {
    double laser_m = 0.3e-3;            ///< [m] profiler, per point
    double dc_lab_percent = 0.5;        ///< [%] drapemeter repeatability
    double dc_seed_percent = 1.0;       ///< [%] fold-pattern (seed) spread of D
    double nodes = 0.75;                ///< [-] node count spread between repeats
    double radius_seed_m = 0.5e-3;      ///< [m] seed spread of a contour's mean radius
    double fold_seed_m = 1.0e-3;        ///< [m] seed spread of the RMS fold amplitude and harmonic magnitudes
    double axis_seed_m = 0.6e-3;        ///< [m] seed spread of the phase-locked cos 2theta / cos 4theta terms
    double hem_m = 4e-3;                ///< [m] hem height from the side photo (edge placement + the arc the camera sees)
    int harmonics = 8;                  ///< harmonic magnitudes compared, k = 2..harmonics (k = 1: the signed a1, b1)
    /// Total sigma of a quantity averaged over `points` laser samples plus a model floor [m].
    double contour_sigma(double floor_m, int points) const;
};

/// One entry of the residual vector.
struct ResidualTerm {
    int record = 0;           ///< index of the record
    std::string kind;         ///< dc | nodes | hem | closure | mean_radius | fold_rms | cos2 | cos4 | harmonic
    double depth_m = 0;       ///< contour terms
    int harmonic = 0;         ///< harmonic terms (k)
    double simulated = 0, measured = 0, sigma = 1; ///< SI (metres, %, count)
    bool smooth = true;       ///< false for the node count (integer): left out of the Jacobian
    bool fitted = true;       ///< in the objective; false = held out (predicted, reported, not fitted)
    double whitened() const { return (simulated - measured) / sigma; }
};

/// Residual terms of one record given the (seed-averaged) simulated features.
/// `closed_fraction[d]` is the fraction of seeds whose slice at depth d closed.
std::vector<ResidualTerm> residual_terms(int record, const DrapeFeatures& measured, const DrapeFeatures& simulated,
                                         const std::vector<double>& closed_fraction, const NoiseModel& noise);

/// Mean of the features of several simulations of the same record (seeds):
/// D, nodes and hem averaged; per depth the contour features averaged over the
/// seeds whose slice closed (all seeds when none did).
DrapeFeatures average_features(const std::vector<DrapeFeatures>& f, std::vector<double>* closed_fraction);

/// Channel of a residual kind: "dc", "nodes", "hem" or "contours".
std::string channel_of(const std::string& kind);
/// Parses "dc,nodes,hem,contours" (any subset); ParameterError on unknown names or an empty set.
std::vector<std::string> parse_channels(const std::string& list);

/// Sum of squared whitened residuals over the fitted terms.
double chi_square(const std::vector<ResidualTerm>& r);

} // namespace drape::estimate
