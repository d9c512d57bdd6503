#pragma once
// The top view: the silhouette of the drape traced along rays from the
// pedestal axis, back-projected onto the height where it really is (a height
// model of the hanging cloth), measured through the shared metric path.
#include "engine/capture/scale.hpp"
#include "engine/capture/segmentation.hpp"
#include "engine/cloth/metrics.hpp"

#include <cmath>
#include <string>
#include <vector>

namespace drape::capture {

/// Height model of the draped surface along each ray from the axis: used to
/// back-project the top-view silhouette onto the height where it really is.
enum class HeightModel {
    Plane,     ///< everything at z = 0 (no correction; for comparison only)
    Chord,     ///< hem at arc length R1-R2 from the disc edge along a straight fibre
    Contours,  ///< laser contours, extrapolated along the last segment to arc length R1-R2
};
const char* to_string(HeightModel m);

/// One term of the stated uncertainty of D [points].
struct UncertaintyTerm {
    std::string name;   ///< edge, scale, scale_reference_height, camera_height, hem_depth
    double points = 0;  ///< 1-sigma contribution to D [percentage points]
    std::string note;   ///< the input sigma, in words
};

/// D under one perspective model, with its uncertainty.
struct PerspectiveValue {
    std::string model;                  ///< none, disc-plane, hem
    bool available = false;
    double dc_percent = std::nan("");
    double area_m2 = std::nan("");
    double uncertainty_percent = std::nan("");
    std::vector<UncertaintyTerm> terms;
    std::string meaning;                ///< one line for a person
};

struct TopView {
    bool measured = false;
    std::string perspective = "hem";    ///< the model D is reported with: none, disc-plane, hem
    std::string perspective_reason;     ///< why that one
    PerspectiveValue uncorrected, disc_plane, hem; ///< every model, always reported
    double specimen_angle = 0;          ///< orientation of a non-round specimen used [rad]
    std::string segmentation_method;
    bool photo_segmentation = false;    ///< the single-photo segmenter (else the lab classifier in `model`)
    double lightness_weight = 1;        ///< photo segmenter: weight of L* against a*, b*
    bool clamp_disc = false;            ///< photo segmenter: the disc top is not cloth-coloured
    cv::Mat region;                     ///< counted pixels (CV_8U, 255), for the overlay
    std::vector<Eigen::Vector2d> limit_px;    ///< the search limit in the image
    std::vector<Eigen::Vector2d> at_limit_px; ///< rays whose edge was found at the search limit
    int rays_at_limit = 0;
    double region_image_fraction = 0;   ///< counted pixels / image pixels
    /// How well a single photo's outline follows a colour edge: the median over the
    /// outline of the L*a*b* distance between the mean colours 2-8 px inside and
    /// outside it, and the share of rays where that distance is weak (below 3 units
    /// or 0.3 of the median). NaN where not checked (lab records, thresholds, masks).
    double outline_edge_contrast = std::nan("");
    double weak_outline_fraction = std::nan("");
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

} // namespace drape::capture
