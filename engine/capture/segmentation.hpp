#pragma once
// Segmentation of a top photo: which pixels are cloth. The classifier is built
// from the image itself (fabric colour on the pedestal top, floor colour on a
// ring outside the specimen's reach).
#include "engine/record/record.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

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

/// Builds the fabric classifier of a top photo (exposed for tests).
FabricModel fabric_model(const record::Record& rec, const record::Camera& cam, const cv::Mat& lab);
/// Fabric probability map (CV_32F, 0..1) of a Lab image under a model.
cv::Mat fabric_probability(const cv::Mat& lab, const FabricModel& m);


/// Manual overrides of the photo segmentation.
struct SegmentOverrides {
    /// "L<60", "L>70", "a>12", "b<-5": cloth is where the CIE L*a*b* channel
    /// passes the threshold (the central component through the disc).
    std::string threshold;
    /// A user mask, same size as the photo: white (>= 200) = cloth, black
    /// (<= 55) = not cloth; anything between = let the segmentation decide
    /// (the white and black parts are then hard seeds). Empty = none.
    cv::Mat mask;
    std::string mask_name; ///< for messages
};

/// What a photo's segmentation counted as cloth.
struct PhotoSegmentation {
    cv::Mat prob;        ///< CV_32F 0..1; the edge is at 0.5 (sub-pixel, from local fabric/background colours)
    cv::Mat region;      ///< CV_8U 255 = counted as cloth (the component through the disc)
    cv::Mat gate;        ///< region dilated a little: where the tracer may look for the 0.5 crossing
    cv::Mat limit;       ///< CV_8U 255 = inside the search limit (where a specimen of this size can reach)
    std::string method;  ///< how the region was found
    double contrast = 0; ///< cloth vs background separation in the features used [Lab units]
    double lightness_weight = 1; ///< weight of L* against a*, b* (< 1: shadows mostly ignored)
    bool clamp_disc = false;     ///< the disc's top is not cloth-coloured (an upper disc / clamp)
    double beyond_limit_fraction = 0; ///< share of cloth-coloured pixels in a band just outside the search limit
    cv::Mat limit_band;          ///< that band (working size), kept when it refused
    /// Pixels whose colour is nearer the cloth's colours than the background's
    /// (CV_8U 255, full size): the colour cue alone, beside GrabCut's region.
    /// Empty for thresholds and masks.
    cv::Mat colour_cloth;
    std::vector<std::string> warnings;
};

/// Segments a single top photo: GrabCut (a graph cut over colour mixtures)
/// seeded with the disc (cloth, counted) and everything beyond the specimen's
/// reach and the image frame (background), in CIE L*a*b* with L* down-weighted
/// when the cloth differs from the background in colour (shadows change L*,
/// hardly a*, b*); the edge is then placed to a fraction of a pixel where the
/// local cloth and background colours mix half and half. `specimen_angle`
/// (NaN = unknown: the search limit is the specimen's largest reach all round).
/// Throws RefusalError when cloth and background cannot be told apart or the
/// user mask does not cover the disc.
PhotoSegmentation segment_photo(const cv::Mat& bgr, const cv::Mat& lab, const record::Record& rec, const record::Camera& cam,
                                const SegmentOverrides& ov, double specimen_angle);

/// The search limit in the image: the flat specimen's edge (+5 %, at least
/// 20 mm, + 3 mm) at the disc top, where the cloth's image must end [px].
std::vector<cv::Point> search_limit_px(const record::Record& rec, const record::Camera& cam, double specimen_angle,
                                       double scale = 1.0, double factor = 1.0);

namespace detail {
/// Binary mask of the fabric component around the pedestal axis (centre and
/// reach in pixels), dilated a little so the sub-pixel edge search is not cut;
/// everything else (boards, specks) is excluded.
cv::Mat central_component(const cv::Mat& prob, const Eigen::Vector2d& centre, double max_radius_px);
} // namespace detail

} // namespace drape::capture
