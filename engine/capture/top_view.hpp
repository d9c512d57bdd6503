#pragma once
// The top view: the silhouette of the drape traced along rays from the
// pedestal axis, back-projected onto the height where it really is (a height
// model of the hanging cloth), measured through the shared metric path.
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

} // namespace drape::capture
