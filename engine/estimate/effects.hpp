#pragma once
// Candidate effects the model may lack, and the tests that decide whether the
// residual of a fit shows one. Each candidate's signature over every
// fitted residual term is computed by the engine at the fitted preset - switch
// the effect on by a small known amount at the fit's own rest states (exact
// rest-state sensitivities for a parameter, a warm re-solve for a switch, a
// re-measurement for the instruments), measure like the lab, difference,
// whiten with the fit's noise - not written by hand. The library is open:
// adding an effect is adding one entry to effect_library().
#include "engine/estimate/objective.hpp"

#include "engine/cloth/params.hpp"

#include <Eigen/Core>

#include <limits>
#include <string>
#include <vector>

namespace drape::estimate {

/// How a candidate's signature is made.
enum class EffectKind {
    Parameter,     ///< a parameter of the table the model holds fixed: dx/d(ln p) from the rest-state sensitivities
    Switch,        ///< an effect switched on at a typical value (a parameter at 0, a contact option): warm re-solve, finite difference
    CameraScale,   ///< the top/side photos' scale off by a fraction: positions scaled, photo channels (D, hem) re-measured
    ProfilerScale, ///< the laser profiler's scale off: contour channels re-measured at scaled positions
    ProfilerAxis,  ///< the profiler (or the specimen) off the pedestal axis: contour channels re-measured at shifted positions (x and y: 2 columns)
    ProfilerTilt,  ///< the profiler's axis tilted against the pedestal's (or the rig off level): contours shifted in proportion to depth (x and y: 2 columns)
    ProfilerDepth, ///< the profiler's height datum off: every cut taken at another depth than declared (contour channels re-measured on the drape moved up)
    Specimen,      ///< the specimen itself uneven (DrapeSetup::density_gradient along x and y): the rest state's responses (cloth::rest_responses)
};

/// One entry of the library.
struct EffectSpec {
    std::string name;        ///< e.g. "buckling"
    std::string family;      ///< measurement | specimen | membrane | bending | contact | declared | numerical
    std::string description; ///< one sentence for the report
    EffectKind kind = EffectKind::Parameter;
    std::vector<cloth::Param> params; ///< Parameter: moved together (relative change); Switch: set to `on_value`
    /// Parameter: the relative change of each of `params` per unit of the effect
    /// (empty: 1 for every one; {+1, -1}: a ratio between two, e.g. warp against weft).
    std::vector<double> weights;
    double on_value = 0;     ///< Switch (parameter at 0): the typical value it is switched on at
    bool disc_grip = false;  ///< Switch: the specimen held on the disc (grip, the limit of large static friction)
    bool vertex_contact = false; ///< Switch: contact at mesh vertices only (the numerical contact resolution)
    bool self_contact = false;   ///< Switch: the folds' self-contact switched on (ModelOptions::self_collision)
    double density_gradient = 0;   ///< Specimen: areal density changing by this fraction per specimen radius (along x, then y)
    std::string amplitude_unit; ///< unit of the fitted amplitude ("relative", "m", "fraction of the switch")
};

/// The candidate effects, in report order.
const std::vector<EffectSpec>& effect_library();

/// The weight of `spec`'s i-th parameter (EffectSpec::weights, 1 when not given).
double effect_weight(const EffectSpec& spec, std::size_t i);

/// Whether the fitted variables already move a parameter effect: its direction
/// (relative change per parameter, EffectSpec::weights) lies in the span of the
/// variables' directions (each an equal relative change of its parameters)
/// restricted to the effect's parameters. Returns the keys of the fitted
/// parameters it involves when it does, "" when it does not (or has no
/// parameters). One parameter fitted on its own covers an effect on it alone;
/// warp and weft tied leave their ratio free.
std::string fitted_by(const EffectSpec& spec, const std::vector<FitVariable>& vars);

/// A candidate's signature: whitened columns over the fit's residual terms
/// (rows in the order of the terms; zero where the effect does not act or the
/// term is not fitted / not smooth).
struct EffectSignature {
    const EffectSpec* spec = nullptr;
    Eigen::MatrixXd columns; ///< rows x k (k = 1, or 2 for x and y: the profiler's axis and tilt, the specimen's weight gradient)
    bool available = true;
    std::string why_not;     ///< when not available (e.g. the model fits that parameter already)
};

/// The verdict on one candidate.
struct EffectCandidate {
    std::string name, family, description;
    int parameters = 1;      ///< columns (degrees of freedom the effect adds)
    /// Matched-filter statistic of the whitened residual on the signature after
    /// the fitted parameters' columns are projected out: signed for one column,
    /// sqrt(delta chi2) for two. Noise alone gives N(0, 1).
    double z = 0;
    /// Likelihood ratio of the refit with the effect freed (Gauss-Newton in the
    /// joint space of the fitted coordinates and the effect: exact to first order).
    double delta_chi2 = 0;
    /// delta_chi2 - k ln(N): > 0 when the effect pays for its extra parameters
    /// (Bayesian information criterion, N fitted smooth terms).
    double information = 0;
    double amplitude = 0;    ///< the refit's size of the effect (first column), in amplitude_unit
    std::vector<double> amplitudes; ///< every column's (x and y for the two-column effects)
    std::string amplitude_unit;
    /// Delta chi2 of the refit verified by draping the preset with the effect
    /// (parameter effects only; NaN otherwise).
    double verified_delta_chi2 = std::numeric_limits<double>::quiet_NaN();
    std::string verdict;     ///< "beyond noise" | "within noise" | "not testable"
    std::string note;
    /// The refit per channel (photos: D and the hem; contours: every contour term):
    /// the share of the signature's weight in the channel and the channel's delta
    /// chi2 of the refit (positive: explained), on the test's scale. An effect is
    /// named only when it explains every channel it reaches (explains_reached).
    struct Channel {
        std::string name;
        double reach = 0;
        double delta_chi2 = 0;
    };
    std::vector<Channel> channels;
    bool explains_reached = true;
};

/// A channel "reached" by a signature holds at least this share of its weight.
inline constexpr double kChannelReach = 0.1;
/// The refit may leave a reached channel this much worse in chi2 (noise) and still explain it.
inline constexpr double kChannelSlack = 1.0;

/// The statistics of the candidates: `J` the fitted coordinates' whitened
/// Jacobian, `r` the whitened residual (same rows; rows outside the test are
/// zero in both), `terms` the number of rows in the test. Beyond noise: delta
/// chi2 above the 3-sigma quantile of chi2 with k degrees of freedom (9.0 for
/// one, 11.8 for two) and information > 0. `chi2_scale` (>= 1): a fit worse
/// than its noise model (chi2 / dof > 1) scales the noise up by that factor -
/// z and delta chi2 are divided by it (as the intervals), the amplitudes are
/// the refit's, unscaled.
/// `channel` (one per row: 0 photos - D and the hem -, 1 contours, -1 neither;
/// empty: not checked) gives each testable candidate its refit per channel
/// (EffectCandidate::channels, explains_reached).
std::vector<EffectCandidate> test_candidates(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                                             const std::vector<EffectSignature>& signatures, int terms, double chi2_scale = 1.0,
                                             const std::vector<int>& channel = {});

/// The named effect: the candidate beyond noise with the largest delta chi2,
/// when its refit explains the residual - the refit's chi2 (chi2 - delta chi2)
/// is within the noise (below dof + 3 sqrt(2 dof)) or the effect explains at
/// least half of the excess - and no other candidate beyond noise comes within
/// 2 of its delta chi2 (per extra parameter 2 more): 2 ln B >= 2 between the two
/// (Kass & Raftery 1995, "positive" evidence). Empty when none does;
/// `unexplained` then says where the residual is.
std::string name_effect(const std::vector<EffectCandidate>& c, double chi2, int dof);

} // namespace drape::estimate
