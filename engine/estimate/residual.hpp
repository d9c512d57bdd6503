#pragma once
// Residual analysis of a fit: is what the model leaves over larger
// than the measurement noise, where is it structured (harmonics, depths,
// channels), and which missing effects is that structure consistent with.
#include "engine/estimate/effects.hpp"
#include "engine/estimate/objective.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace drape::estimate {

struct ResidualAnalysis {
    double chi2 = 0;
    int dof = 0;                      ///< residual terms minus fitted coordinates
    bool exceeds_noise = false;       ///< chi2 beyond dof + 3 sqrt(2 dof), or one channel / harmonic beyond its own 3-sigma chi2 bound, or a candidate effect beyond noise
    bool exceeds_noise_by_residual = false; ///< the same without the candidate effects' tests
    double rms_m = 0;                 ///< RMS of the contour residuals in metres (radius, folds, harmonics)
    double rms_whitened = 0;          ///< RMS of all whitened residuals (1 = at the noise)
    std::vector<int> dominant_harmonics; ///< harmonics whose whitened residual RMS exceeds 2, largest first
    std::vector<double> harmonic_rms; ///< whitened RMS per harmonic k = 1..K (index k-1)
    std::vector<std::pair<double, double>> depth_rms; ///< (depth [m], whitened RMS of that depth's terms)
    std::vector<std::pair<std::string, double>> kind_rms; ///< whitened RMS per channel
    double fitted_rms_whitened = 0;   ///< over the fitted terms
    double held_out_rms_whitened = 0; ///< over the held-out terms (predictions); 0 when none
    int held_out_terms = 0;
    double dc_error_percent = 0;      ///< mean simulated - measured D
    double node_error = 0;            ///< mean simulated - measured nodes
    std::vector<std::string> candidate_effects; ///< names, see docs/estimate.md
    std::vector<std::string> evidence;           ///< one sentence per candidate, same order
    /// Matched-filter statistics: the whitened residual projected on the unit
    /// signature of an effect, z = s.w / |s|. With noise alone |z| is at most
    /// about N(0, 1) (the sigmas are noise bounds), so z > 3 is a structured
    /// residual even when the total chi2 is not large. Keys, in this order:
    /// rim_wrapping, specimen_off_centre (a common shift of every depth's signed a1,
    /// b1 per record; z = sqrt of a chi2 with 2 degrees of freedom per record, beyond
    /// noise above its 3-sigma quantile, 11.83 = 3.44^2 for one record).
    std::vector<std::pair<std::string, double>> signature_z;
    /// Which test put the residual beyond noise (e.g. "harmonic 3: chi2 18.1 over 5 terms").
    std::vector<std::string> exceeds_because;
    /// The candidate effects tested against the residual with engine-made
    /// signatures (effects.hpp), in library order; empty when not run.
    std::vector<EffectCandidate> candidates;
    /// The effect the refit names (name_effect), or empty.
    std::string named_effect;
    /// When the residual is beyond noise and no effect explains it: where it is.
    std::string unexplained;
};

/// Analyses the residual terms of a fit with `fitted` coordinates. `J`: the
/// whitened Jacobian of the fitted coordinates at the optimum, one row per term
/// (rows of terms the fit did not fit or cannot differentiate zero), or empty: the
/// matched filters then divide by the signature's norm, not by the norm of its part
/// the fit cannot absorb (conservative: z understated where the two overlap).
ResidualAnalysis analyse_residual(const std::vector<ResidualTerm>& terms, int fitted, const Eigen::MatrixXd& J = {});

nlohmann::json residual_to_json(const ResidualAnalysis& a);

} // namespace drape::estimate
