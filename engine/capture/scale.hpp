#pragma once
// The scale of a single top photo, as a camera. Whatever tells the scale (the
// support disc's rim seen in the photo, printed ArUco markers or a chessboard
// at a declared height, a known number of pixels per mm, or the lab's full
// calibration) becomes one pinhole camera in the record's world frame (origin
// = centre of the disc top, z up), plus what is NOT known about it: the camera
// height above the disc, the height of the scale reference, the scale's own
// error. The top-view tracer then works on that camera whatever the source,
// and the uncertainty of D is computed from those unknowns.
//
// A single-camera world frame has +x = image right and +y = image up (for a
// camera looking down), so node angles and a rectangle's orientation are
// measured from the photo's horizontal, anticlockwise.
#include "engine/record/record.hpp"

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include <filesystem>
#include <cmath>
#include <optional>
#include <string>
#include <vector>

namespace drape::capture {

/// The support disc's rim found in the photo (an ellipse; a circle seen from
/// straight above).
struct DiscRim {
    Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
    double radius_px = 0;        ///< mean radius of the fitted circle [px]
    double axis_ratio = 1;       ///< minor / major axis of the fitted ellipse [-] (cos of the tilt)
    double ellipse_angle_deg = 0;///< major axis direction in the image [deg]
    double ray_fraction = 0;     ///< fraction of the rays that found the rim [-]
    double rms_px = 0;           ///< RMS distance of the rim points to the circle [px]
    std::string edge;            ///< which image edge gave it ("L* darker outside", ...)
    std::vector<Eigen::Vector2d> points_px; ///< the rim points used
    bool declared = false;       ///< position given in meta.json (top_photo.disc_px), not found
};

/// A printed marker found in the photo.
struct MarkerSeen {
    int id = -1;
    std::vector<Eigen::Vector2d> corners_px; ///< 4 corners, ArUco order (top-left, top-right, bottom-right, bottom-left)
};

/// The camera of a top photo and what is known and not known about it.
struct ViewGeometry {
    record::Camera camera;             ///< world -> image (no distortion)
    record::ScaleSource source = record::ScaleSource::Calibration;
    std::string source_text;           ///< one line: what gave the scale
    bool single_camera = false;        ///< built here (not the lab's calibrated rig)
    // The scale reference.
    double reference_height = 0;       ///< z of the plane the scale was read in [m]
    double reference_height_sigma = 0; ///< [m]
    double scale_px_per_m = 0;         ///< image scale in that plane [px/m]
    double scale_sigma_rel = 0;        ///< relative error of that scale [-]
    // The camera height above the disc top.
    double camera_height = 0;          ///< [m]
    double camera_height_sigma = 0;    ///< [m]
    std::string camera_height_source;  ///< declared, calibration, two heights, focal length, assumed (...)
    bool camera_height_known = true;   ///< false when only a lens prior gives it
    // Where the disc centre is in the image.
    Eigen::Vector2d centre_px = Eigen::Vector2d::Zero();
    std::string centre_source;
    /// When the centre is the cloth's centroid (no rim found): how far the disc's
    /// centre can lie from it, the disc being inside the cloth's outline (the
    /// largest distance, and the RMS distance over every such centre) [m, at the
    /// disc top]. NaN otherwise, or when the rough mask is too small to hold the disc.
    double centre_bound = std::nan("");
    double centre_sigma = std::nan("");
    std::optional<DiscRim> disc;
    std::vector<MarkerSeen> markers;
    std::vector<Eigen::Vector2d> board_corners_px; ///< chessboard corners used
    /// The separate calibration photo the markers or chessboard were found in
    /// (ScaleCalibration::photo); "" when they were found in this photo.
    std::string calibration_photo;
    // Internal: the plane model the camera was built from (single camera).
    double focal_px = 0;
    Eigen::Vector3d plane_normal_cam = Eigen::Vector3d(0, 0, -1); ///< world +z in camera coordinates
    double reference_distance = 0;     ///< camera to the reference plane along its normal [m]
    std::vector<std::string> warnings;
};

/// Why a photo cannot be measured: which check failed, and what to try.
struct Refusal {
    std::string check;   ///< short id: disc-not-found, markers-not-found, border, search-limit, region-size, dc-range, low-contrast, no-fabric, ...
    std::string message; ///< what was found
    std::string remedy;  ///< what the user can do
};

/// Thrown by the view and segmentation steps; measure_record turns it into
/// Measurement::refused.
struct RefusalError : std::runtime_error {
    Refusal refusal;
    explicit RefusalError(Refusal r) : std::runtime_error(r.message), refusal(std::move(r)) {}
};

/// A scale reference (printed markers or a chessboard) found once in a separate
/// calibration photo, taken with the same fixed camera at the same image size as
/// the photos it is used for. Each of those photos is then solved as if the
/// reference had been found in it: the same corners, so the same plane, px/mm,
/// reference height and sigma; the disc, the lens (EXIF) and the camera height
/// are still each photo's own.
struct ScaleCalibration {
    std::string photo;          ///< the calibration photo, as named to the user
    int width = 0, height = 0;  ///< its size [px]; every photo it is used for must have the same
    record::TopPhoto reference; ///< the declaration it was read with: source, size, layout, dictionary, height (image unused)
    std::vector<MarkerSeen> markers;               ///< the markers found in it
    std::vector<Eigen::Vector2d> board_corners_px; ///< the chessboard corners found in it
    double scale_px_per_m = 0;  ///< the reference's image scale in its plane [px/m]
    double scale_sigma_rel = 0; ///< relative error of that scale [-]
    std::string description;    ///< what was found, one line
};

/// Finds the markers or the chessboard that `reference` declares (its scale
/// source, sizes, layout and height; reference.image is not used) in the photo
/// at `photo`. Throws FileError naming the photo when it cannot be read or the
/// reference is not in it, ParameterError for a scale source that is not a
/// printed pattern (the disc rim is found in each photo; px/mm needs no photo).
ScaleCalibration read_scale_calibration(const record::TopPhoto& reference, const std::filesystem::path& photo);

/// Throws FileError naming both photos and both sizes unless the photo `name` is
/// `width` x `height` px, the size of the calibration photo.
void check_calibration_size(const ScaleCalibration& cal, const std::string& name, int width, int height);

/// The camera of a single-camera record's top photo from its scale source.
/// `rough_cloth` is a rough mask of the cloth (for the disc search; may be
/// empty). With `calibration` the markers or chessboard are not searched in the
/// photo: the calibration photo's are used, with its declaration (the record's
/// own scale source is then not used). Throws RefusalError when the scale
/// reference is not in the photo, FileError for an unusable declaration or a
/// calibration photo of another size.
ViewGeometry solve_view(const record::Record& rec, const cv::Mat& bgr, const cv::Mat& lab, const cv::Mat& rough_cloth,
                        const ScaleCalibration* calibration = nullptr);

/// The same camera with the camera height changed to `H` [m], keeping the
/// image of the scale reference plane (what the photo measured) fixed.
record::Camera camera_with_height(const ViewGeometry& g, double H);
/// When the disc centre is the cloth's centroid (no rim found): how far the
/// disc's centre can lie from it (ViewGeometry::centre_bound, centre_sigma). The
/// cloth covers the disc, so the disc's image lies inside the counted region
/// (holes filled) and its centre at least the disc's smallest image radius from
/// the region's edge - the distance transform says where. Returns the warning
/// to print ("" when the centre is not the centroid).
std::string bound_disc_centre(const record::Record& rec, const cv::Mat& region, ViewGeometry& g);

/// Finds the disc rim around `centre_guess` [px] with a radius in
/// [r_min, r_max] [px]: the strongest circular step edge of L*, a* or b*
/// (RANSAC over the edge points of 360 rays). nullopt when no circle is
/// supported by at least half the rays.
std::optional<DiscRim> find_disc_rim(const cv::Mat& lab, const Eigen::Vector2d& centre_guess, double r_min, double r_max);

/// ArUco markers of a named dictionary ("DICT_4X4_50", ...). Throws FileError
/// for an unknown dictionary name.
std::vector<MarkerSeen> find_markers(const cv::Mat& bgr, const std::string& dictionary);

/// Rough cloth mask of a photo without any geometry (GrabCut from the image
/// frame inwards, the component nearest the image centre), for the disc search.
cv::Mat rough_cloth_mask(const cv::Mat& bgr);

} // namespace drape::capture
