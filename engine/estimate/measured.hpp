#pragma once
// What the fit compares against: the measured quantities of one drape-test
// record (lab data or a synthetic record made by the engine), and the
// phase-independent features extracted from them. Measured and simulated drapes
// go through the same feature code (drape_features), so the objective compares
// like with like.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/metrics.hpp"
#include "engine/record/record.hpp"

#include <Eigen/Core>

#include <array>
#include <limits>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace drape::estimate {

/// One laser cross-section: the outer envelope of the cut at z = -depth_m.
struct MeasuredContour {
    double depth_m = 0;           ///< [m] below the pedestal top
    cloth::RadialProfile profile; ///< r(theta) [m], theta_k = 2 pi k / N from +x (warp) towards +y (weft)
};

/// Measured quantities of one record. NaN / -1 mark quantities the record lacks.
struct MeasuredDrape {
    std::string id;                  ///< record id (folder name)
    std::string source;              ///< folder or "synthetic"
    double sample_diameter = 0.30;   ///< [m] D1
    double disc_diameter = 0.15;     ///< [m] D2
    double pedestal_height = 0.12;   ///< [m]
    double areal_density = 0.2;      ///< [kg/m^2] declared by the lab, not fitted
    double thickness = 0.5e-3;       ///< [m] declared by the lab
    double drape_coefficient_percent = std::numeric_limits<double>::quiet_NaN(); ///< drapemeter reading [%]
    double laser_sigma_m = 0.3e-3;   ///< [m] profiler repeatability (1 sigma per coordinate)
    double hem_min_z = std::numeric_limits<double>::quiet_NaN(); ///< [m] lowest hem point (side view), if known
    /// The pedestal's diameter in the side photo and its uncertainty [m] (NaN: no
    /// side photo); the fit simulates disc_diameter, as declared.
    double pedestal_measured_diameter = std::numeric_limits<double>::quiet_NaN();
    double pedestal_measured_sigma = std::numeric_limits<double>::quiet_NaN();
    int node_count = -1;             ///< folds, if the record states them (photo); else taken from the contours
    std::string node_source;         ///< where node_count came from
    /// Node detector settings of the photo's count; simulations are counted with the same settings.
    cloth::MetricOptions node_metric_options;
    /// True when hem_min_z is the side photo's lowest hem point seen in front of
    /// the pedestal (y < 0, |x| < R2): simulations are measured over the same arc.
    bool hem_from_side_view = false;
    double photo_drape_coefficient_percent = std::numeric_limits<double>::quiet_NaN(); ///< D from the top photo [%]
    std::vector<std::string> notes;  ///< what the capture layer said (warnings, what it could not measure)
    std::vector<MeasuredContour> contours; ///< closed cuts, increasing depth
    /// Measurement-model component "profiler axis": when set, the contour
    /// stacks of the record and of every simulation are re-centred on their own
    /// axis (the mean area centroid of the closed cuts) before features are taken,
    /// so an offset of the profiler's (or the specimen's) axis from the pedestal
    /// axis is estimated instead of read as fold shape. Off by default: a centred
    /// stack keeps its harmonic 1, which is information about the drape.
    bool recentre_contours = false;
    /// Measurement-model component "profiler axis tilted": as
    /// recentre_contours, with an axis that moves linearly with depth - the cuts'
    /// centroids fitted by offset + depth x tilt (least squares; needs two closed
    /// cuts, else the mean) and each cut moved by its line's point. For a profiler
    /// whose axis is tilted against the pedestal's, or a drape that leans.
    bool untilt_contours = false;
    std::optional<record::Camera> top_camera; ///< calibration of the top photo, for overlays
    std::string top_photo;           ///< path of top.jpg ("" if none)

    /// The drape set-up this record was measured on, simulated at `grid` with perturbation `seed`.
    cloth::DrapeSetup setup(int grid, std::uint64_t seed) const;
    std::vector<double> depths() const;
};

/// The fold branch a measured node count names for cloth::on_fold_branch: the
/// rounded count when it is in 2..16, else 0 (start from the random mix).
int measured_fold_branch(double node_count);

/// Reads a lab record folder through the one record reader (record::read_record,
/// record::read_contours; format of shared/data/drape-lab/README.md). Throws
/// FileError / ParameterError naming the file, field and value. With
/// `use_photos` the node count comes from the top photo and the hem height from
/// the side photo (capture::measure_record); otherwise (or when the photos
/// cannot be measured) the node count is that of the deepest contour and the
/// hem is not used.
MeasuredDrape load_record(const std::string& dir, bool use_photos = true);

/// Turns a simulated drape into a record, as the lab would measure it: the
/// drapemeter D of the shadow, the closed slices (Gaussian laser noise of
/// `laser_sigma` [m] added radially, from `noise_seed`), the hem's lowest point.
MeasuredDrape synthesize_record(const cloth::DrapeResult& r, const cloth::DrapeSetup& setup, const cloth::FabricParams& p,
                                double laser_sigma_m, std::uint64_t noise_seed, const std::string& id = "synthetic");

/// Phase-independent features of one contour. Fold positions are random from
/// drape to drape, so only quantities that do not depend on where the folds
/// fall are kept: mean radius, RMS fold amplitude, harmonic magnitudes, the
/// signed cos(2 theta) and cos(4 theta) coefficients (warp/weft anisotropy
/// locks their phase to the fabric axes), and the signed first harmonic
/// a_1, b_1 (locked to the stand: the contour's shift off the pedestal axis,
/// x and y; zero but for the folds' irregularity on a centred stand).
struct ContourFeatures {
    double depth_m = 0;  ///< [m]
    bool closed = false; ///< every ray hit
    double mean_radius_m = 0;
    double fold_rms_m = 0; ///< RMS of r - mean [m]
    double cos2_m = 0, cos4_m = 0; ///< signed a_2, a_4 [m]
    double cos1_m = 0, sin1_m = 0; ///< signed a_1, b_1 [m]
    std::vector<double> magnitudes_m; ///< |c_k|, k = 1..K [m]
    int node_count = 0;                ///< crests of this contour (shared node detector)
    cloth::FourierSeries series;       ///< fit with kFeatureHarmonics terms
};

inline constexpr int kFeatureHarmonics = 16;

ContourFeatures contour_features(const cloth::RadialProfile& p, double depth_m, int harmonics = kFeatureHarmonics);

/// The lowest point of a hem seen over the angles [a, b] [rad, within -pi..pi]:
/// the hem as the curve through its vertices in order of angle (theta, z), read
/// between two vertices at the window's edges, so it is continuous in the
/// vertices' positions and in the window as long as no two vertices trade places
/// in angle next to an edge (a hem folded over in the top view). (Taking a
/// vertex's z whole the moment it enters the window made the side view's hem
/// jump by millimetres for a nanometre's move: the fit's Jacobian read that as a
/// slope of metres per decade of the bendings.) Vertices with a non-finite angle
/// or height are left out; NaN without vertices or with a > b.
double hem_min_over_arc(const std::vector<double>& theta, const std::vector<double>& z, double a, double b);

/// Features of a whole drape: D [%], nodes, hem, contours at the measured depths.
struct DrapeFeatures {
    double drape_coefficient_percent = std::numeric_limits<double>::quiet_NaN();
    double node_count = -1;   ///< mean over seeds for simulations
    double hem_min_z = std::numeric_limits<double>::quiet_NaN(); ///< [m]
    std::vector<ContourFeatures> contours;
    /// Axis of the contour stack removed by MeasuredDrape::recentre_contours [m] (zero when not re-centred).
    Eigen::Vector2d axis_offset_m = Eigen::Vector2d::Zero();
    /// Tilt of that axis [rad, as dx/d(depth), dy/d(depth)] removed by MeasuredDrape::untilt_contours.
    Eigen::Vector2d axis_tilt = Eigen::Vector2d::Zero();
};

/// Shifts the closed profiles of a contour stack so that the mean area centroid
/// of the closed ones is at the origin; returns the shift removed [m].
Eigen::Vector2d recentre_stack(std::vector<cloth::RadialProfile>& profiles);

/// The same with an axis that moves with depth: the closed cuts' area centroids
/// fitted by offset + depth x tilt (least squares over the cuts at `depths` [m];
/// the mean when fewer than two are closed or they share a depth), each closed
/// cut moved by its depth's point. Returns the offset at depth 0 [m]; `tilt`
/// gets the slope [m per m of depth].
Eigen::Vector2d untilt_stack(std::vector<cloth::RadialProfile>& profiles, const std::vector<double>& depths, Eigen::Vector2d& tilt);

/// Features of a measured record. The node count is the record's own if it
/// states one; otherwise the crests of the deepest closed contour.
DrapeFeatures drape_features(const MeasuredDrape& m);

/// Features of a simulated drape at the record's depths, measured the same way
/// (node count from the slice at the deepest measured depth when the record has
/// no photo count, else from the shadow outline, as the photo is).
DrapeFeatures drape_features(const cloth::DrapeResult& r, const MeasuredDrape& like);

/// The parameters of `base` with areal density and thickness from the record.
cloth::FabricParams params_for_record(const cloth::FabricParams& base, const MeasuredDrape& m);

} // namespace drape::estimate
