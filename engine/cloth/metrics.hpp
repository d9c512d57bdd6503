#pragma once
// Drape metrics on a 2-D contour in metres: the one metric path shared by
// photos (segment -> contour -> here) and simulations (project mesh -> contour
// -> here), so both are measured by the same code.
//
// Frame: the pedestal axis is the origin; theta is measured from +x (warp)
// towards +y (weft), in radians.
#include "engine/cloth/mesh.hpp"

#include <Eigen/Core>

#include <optional>
#include <vector>

namespace drape::cloth {

/// Closed polygon in the horizontal plane [m], vertices in order (either orientation).
using Polygon2 = std::vector<Eigen::Vector2d>;

/// r(theta) sampled at theta_k = 2*pi*k/N [m]. NaN marks a ray with no hit.
struct RadialProfile {
    std::vector<double> r;
    int size() const { return static_cast<int>(r.size()); }
    double theta(int k) const;
    bool complete() const; ///< every ray hit
};

/// Outermost intersection of each ray from the origin with the polygon's edges.
RadialProfile radial_profile(const Polygon2& poly, int samples = 720);
/// The polygon traced by a radial profile (rays with no hit are skipped).
Polygon2 polygon_from_profile(const RadialProfile& p);

/// Fourier series r(theta) = a0 + sum_k a_k cos(k theta) + b_k sin(k theta) [m].
struct FourierSeries {
    double a0 = 0;
    std::vector<double> a, b; ///< index k-1 holds harmonic k
    int harmonics() const { return static_cast<int>(a.size()); }
    double magnitude(int k) const; ///< sqrt(a_k^2 + b_k^2) [m], k >= 1
    double evaluate(double theta) const;
};

/// Least-squares Fourier fit of a profile (NaN rays ignored) with `harmonics` terms.
FourierSeries fourier_fit(const RadialProfile& p, int harmonics);

/// Least-squares Fourier fits of one profile for every number of harmonics up
/// to a maximum. The fits are nested (K harmonics use the leading 2K+1 columns
/// of one design matrix), so the basis and its normal matrix are built once;
/// choosing K by trying each (choose_harmonics, the contour levels' noise
/// floor) then costs one small factorisation per K instead of a new design
/// matrix and product (m x (2K+1)^2 flops) each time. Same numbers as
/// fourier_fit to rounding.
class FourierLeastSquares {
public:
    /// `max_harmonics` is clamped as fourier_fit clamps (an overdetermined system).
    FourierLeastSquares(const RadialProfile& p, int max_harmonics);
    int max_harmonics() const { return max_harmonics_; }
    int hit_rays() const { return static_cast<int>(y_.size()); }
    /// The fit with min(harmonics, max_harmonics()) terms; a0 NaN without hit rays.
    FourierSeries fit(int harmonics) const;
    /// RMS of profile minus `s` over the hit rays [m] (s must have at most max_harmonics() terms).
    double residual_rms(const FourierSeries& s) const;

private:
    int max_harmonics_ = 0;
    Eigen::MatrixXd basis_; ///< hit ray x (1, cos 1th, sin 1th, ..., cos Kth, sin Kth)
    Eigen::VectorXd y_;     ///< r of the hit rays
    Eigen::MatrixXd normal_;
    Eigen::VectorXd rhs_;
};

/// Chooses the number of harmonics from the data: the smallest K whose residual
/// is consistent with the noise `noise_sigma` [m]; when no K up to
/// `max_harmonics` (default: a third of the sampled rays) reaches it, the K
/// with the best BIC. Reaching the noise takes priority over the BIC.
int choose_harmonics(const RadialProfile& p, double noise_sigma, int max_harmonics = -1);
/// The same choice over the fits `lsq` offers (K up to lsq.max_harmonics()).
int choose_harmonics(const FourierLeastSquares& lsq, double noise_sigma);

/// RMS of profile minus series over the hit rays [m].
double fourier_residual_rms(const RadialProfile& p, const FourierSeries& s);

struct MetricOptions {
    /// Harmonics kept when smoothing r(theta) before looking for nodes. Folds of
    /// a 300 mm drape have 3..14 nodes, so 24 keeps their shape and drops pixel noise.
    int smoothing_harmonics = 24;
    /// A node (fold crest) must rise above both neighbouring troughs by at least
    /// max(min_prominence_m, relative_prominence * (max r - min r)).
    double min_prominence_m = 1.5e-3;
    /// 0.10: the weak folds of the lab's limpest records (checked by eye on the
    /// set-a overlays) stand out by 10-15 % of the range; counts are the same for
    /// 0.05-0.10 there.
    double relative_prominence = 0.10;
    int samples = 720;
};

struct DrapeMetrics {
    double shadow_area_m2 = 0;            ///< area of the outline (vertical projection), disc included
    double drape_coefficient_percent = 0; ///< (A - pi R2^2) / (pi R1^2 - pi R2^2) * 100
    int node_count = 0;
    std::vector<double> node_angles_rad;  ///< crest angles, increasing in [0, 2 pi)
    std::vector<double> node_amplitudes_m;///< crest radius minus mean radius
    double mean_radius_m = 0, min_radius_m = 0, max_radius_m = 0;
    RadialProfile profile;                ///< raw r(theta) of the outline
    FourierSeries fourier;                ///< fit with MetricOptions::smoothing_harmonics terms
};

/// Metrics of a shadow outline. R1 = specimen radius, R2 = disc radius [m].
DrapeMetrics drape_metrics(const Polygon2& outline, double R1, double R2, const MetricOptions& opt = {});

/// Node detection on a radial profile (used by drape_metrics).
void find_nodes(const RadialProfile& p, const MetricOptions& opt, DrapeMetrics& out);

// ---- from a simulated mesh --------------------------------------------------

/// Outline of the vertical projection (shadow) of a mesh: r_max(theta) over all
/// projected triangles, traced as a polygon with `samples` vertices.
Polygon2 shadow_outline(const Positions& X, const Triangles& F, int samples = 1440);

/// Outer envelope of the horizontal cut of the mesh by the plane z = z_plane [m],
/// as r(theta) along rays from the axis (the laser profiler's definition). Rays
/// that miss are NaN; complete() says whether the cut closes around the axis.
RadialProfile slice_profile(const Positions& X, const Triangles& F, double z_plane, int samples = 360);

/// Hem (boundary) heights: z of each boundary vertex and its angle [m, rad].
struct HemProfile {
    std::vector<double> theta, z;
    double min_z = 0, max_z = 0, mean_z = 0;
};
HemProfile hem_profile(const Positions& X, const std::vector<char>& boundary);

} // namespace drape::cloth
