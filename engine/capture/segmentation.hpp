#pragma once
// Segmentation of a top photo: which pixels are cloth. The classifier is built
// from the image itself (fabric colour on the pedestal top, floor colour on a
// ring outside the specimen's reach).
#include "engine/record/record.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

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

/// Builds the fabric classifier of a top photo (exposed for tests).
FabricModel fabric_model(const record::Record& rec, const record::Camera& cam, const cv::Mat& lab);
/// Fabric probability map (CV_32F, 0..1) of a Lab image under a model.
cv::Mat fabric_probability(const cv::Mat& lab, const FabricModel& m);


namespace detail {
/// Binary mask of the fabric component around the pedestal axis (centre and
/// reach in pixels), dilated a little so the sub-pixel edge search is not cut;
/// everything else (boards, specks) is excluded.
cv::Mat central_component(const cv::Mat& prob, const Eigen::Vector2d& centre, double max_radius_px);
} // namespace detail

} // namespace drape::capture
