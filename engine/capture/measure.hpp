#pragma once
// From a drape-lab record to calibrated measurements: top-view segmentation,
// perspective-corrected shadow outline -> shared drape metrics, side-view hem,
// laser-contour Fourier series. Everything in metres, world frame.
#include "engine/capture/calibrate.hpp"
#include "engine/record/record.hpp"
#include "engine/cloth/metrics.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace drape::capture {

/// Fabric-vs-background classifier built from the image itself: fabric colour
/// sampled on the pedestal top (always covered), floor colour sampled on a ring
/// outside the specimen's reach. p = 1 on fabric, 0 on floor/shadow.
struct FabricModel {
    cv::Vec3d fabric_lab, floor_lab; ///< CIE L*a*b* (L 0..100)
    double fabric_L_sd = 0;          ///< spread of L* on the fabric sample
    bool chromatic = true;           ///< classify by chroma (else by darkness)
    double contrast = 0;             ///< separation fabric/floor in the chosen feature [Lab units]
};

/// Height model of the draped surface along each ray from the axis: used to
/// back-project the top-view silhouette onto the height where it really is.
enum class HeightModel {
    Plane,     ///< everything at z = 0 (no correction; for comparison only)
    Chord,     ///< hem at arc length R1-R2 from the disc edge along a straight fibre
    Contours,  ///< laser contours, extrapolated along the last segment to arc length R1-R2
};
const char* to_string(HeightModel m);

struct TopView {
    bool measured = false;
    FabricModel model;
    HeightModel height_model = HeightModel::Chord;
    cloth::Polygon2 outline;            ///< corrected shadow outline [m], one vertex per ray
    std::vector<double> outline_z;      ///< height at which each vertex was found [m]
    std::vector<double> outline_arc;    ///< arc length from the disc edge of each vertex [m] (model)
    std::vector<Eigen::Vector2d> outline_px; ///< the silhouette point in the image [px]
    cloth::DrapeMetrics metrics;        ///< shared metric path on `outline`
    double dc_plane_percent = 0;        ///< D without perspective correction (outline on z = 0)
    double dc_chord_percent = 0;        ///< D with the chord height model
    double dc_contours_percent = std::nan(""); ///< D with the contour height model (NaN without contours)
    double dc_uncertainty_percent = 0;  ///< stated remaining error of D [points] (edge + height model)
    double dc_edge_term = 0;            ///< part of it from 0.5 px edge placement [points]
    double dc_per_metre_height = 0;     ///< dD/dz of a uniform height-model error [points/m]
    double height_error_m = 0;          ///< height-model error used for the uncertainty [m]
    int rays_beyond_reach = 0;          ///< rays whose edge lies beyond the model's hem (flag)
    std::vector<std::string> warnings;
};

struct SideView {
    bool measured = false;
    int columns = 0;                      ///< columns where the hem was found in front of the pedestal
    double hem_min_z = std::nan("");      ///< lowest hem point seen in front of the pedestal [m]
    double hem_min_theta = std::nan("");  ///< its angle [rad]
    double model_rms_diff = std::nan(""); ///< RMS(side z - top height model z) at those points [m]
    std::vector<Eigen::Vector2d> hem_px;  ///< the traced hem in the side image [px]
    std::vector<Eigen::Vector3d> hem_world; ///< the same in the world [m]
    std::vector<std::string> warnings;
};

struct ContourLevel {
    double depth = 0;             ///< below the pedestal top [m]
    int points = 0;               ///< rays with data
    bool complete = false;        ///< all rays hit
    double mean_radius = 0;       ///< Fourier a0 [m]
    int harmonics = 0;            ///< chosen from the data (choose_harmonics)
    cloth::FourierSeries fit;     ///< r(theta) [m]
    double residual_rms = 0;      ///< [m]
    double noise_sigma = 0;       ///< declared repeatability [m]
    double max_jump = 0;          ///< largest |r_k+1 - r_k| between neighbouring rays [m] (overhangs)
};

struct Measurement {
    std::string specimen_id;
    std::optional<double> lab_dc_percent;
    std::optional<Calibration> top_calibration;
    TopView top;
    SideView side;
    std::vector<ContourLevel> contours;
    std::optional<double> hem_min_height;  ///< lowest hem point z [m] (< 0 below the pedestal top)
    std::string hem_min_source;            ///< which evidence gave it
    std::vector<std::string> measured;     ///< what was measured
    std::vector<std::string> not_measured; ///< "what: why"
    std::vector<std::string> warnings;
    cv::Mat top_image, side_image;         ///< kept for overlays (empty when absent)
};

struct MeasureOptions {
    int rays = 720;                 ///< rays traced around the axis for the outline
    bool calibrate = true;          ///< measure the top pose from the chessboards
    /// Node detection etc. A crest counts as a node when it rises 10 % of the
    /// outline's radial range above both neighbouring troughs (the shared
    /// default is 15 %): on the set-a overlays 0.05 to 0.10 all give the counts a
    /// person makes by eye, 0.15 drops the weak folds of DL-A01 and DL-A10.
    cloth::MetricOptions metrics = [] {
        cloth::MetricOptions m;
        m.relative_prominence = 0.10;
        return m;
    }();
};

/// Segments and measures a record. Missing or broken optional files
/// (photos, contours) are listed in not_measured; a broken meta.json throws.
Measurement measure_record(const record::Record& rec, const MeasureOptions& opt = {});

/// Builds the fabric classifier of a top photo (exposed for tests).
FabricModel fabric_model(const record::Record& rec, const record::Camera& cam, const cv::Mat& lab);
/// Fabric probability map (CV_32F, 0..1) of a Lab image under a model.
cv::Mat fabric_probability(const cv::Mat& lab, const FabricModel& m);

/// JSON report (SI units with the unit in each key name).
nlohmann::ordered_json to_json(const Measurement& m);

/// Overlay on the top photo: traced outline, nodes, pedestal circle, specimen circle.
cv::Mat draw_top_overlay(const record::Record& rec, const Measurement& m);

/// Gider (2004) KES regression quoted in the seed paper (section 5.2). Inputs in
/// the KES-FB units: two_hb [gf cm/cm], miu [-], g [gf/(cm deg)], rt [%],
/// wc [gf cm/cm^2], rc [%], t0 [mm], emc [%], w [mg/cm^2]. Returns DC [%].
struct KesValues {
    double two_hb = 0, miu = 0, g = 0, rt = 0, wc = 0, rc = 0, t0 = 0, emc = 0, w = 0;
};
double gider_drape_coefficient(const KesValues& k);

} // namespace drape::capture
