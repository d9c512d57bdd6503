#pragma once
// Reader of a drape-lab record (shared/data/drape-lab/README.md): meta.json,
// top/side/iso photographs and the laser contours. Every length read from the
// record (mm) is converted to metres here, at the edge; the rest of the capture
// layer works in SI units in the world frame (origin = centre of the pedestal
// top, z up, x = warp).
#include "engine/cloth/metrics.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace drape::capture {

/// Pinhole camera, OpenCV convention (x right, y down, z forward), no distortion
/// is assumed by the projection helpers (the README declares none; a record with
/// non-zero coefficients is undistorted through OpenCV where images are read).
struct Camera {
    std::string name;            ///< station name: top, side, iso
    std::string image;           ///< image file name inside the record
    int width = 0, height = 0;   ///< image size [px]
    double fx = 0, fy = 0;       ///< focal lengths [px]
    double cx = 0, cy = 0;       ///< principal point [px] (pixel centres at integers)
    std::vector<double> dist;    ///< OpenCV distortion coefficients [-]
    Eigen::Matrix3d R = Eigen::Matrix3d::Identity(); ///< world -> camera rotation
    Eigen::Vector3d t = Eigen::Vector3d::Zero();     ///< world -> camera translation [m]

    /// Pixel position of a world point [m] -> [px]. Behind-camera points give NaN.
    Eigen::Vector2d project(const Eigen::Vector3d& X) const;
    /// Optical centre in the world frame [m].
    Eigen::Vector3d centre() const { return -R.transpose() * t; }
    /// Unit direction (world frame) of the ray through pixel `px` [px].
    Eigen::Vector3d ray(const Eigen::Vector2d& px) const;
    /// Intersection of the ray through `px` with the horizontal plane z = `z` [m].
    /// nullopt when the ray is parallel to or points away from the plane.
    std::optional<Eigen::Vector3d> backproject_to_plane(const Eigen::Vector2d& px, double z) const;
    cv::Matx33d K() const { return {fx, 0, cx, 0, fy, cy, 0, 0, 1}; }
    bool has_distortion() const;
};

/// A chessboard printed on the floor sheet (README "Calibration boards").
struct Board {
    std::string name;
    double x0 = 0, y0 = 0;  ///< corner with minimum x and y [m]
    int nx = 0, ny = 0;     ///< squares along x, y
    double square = 0;      ///< square edge [m]
    double z = 0;           ///< plane of the board [m]
};

/// Laser cross-section contours: one radial profile per depth.
struct ContourStack {
    std::vector<double> depths;                       ///< depth below the pedestal top [m] (> 0)
    std::vector<cloth::RadialProfile> profiles;       ///< r(theta_k) [m], theta_k = 2 pi k / N
    std::vector<std::vector<Eigen::Vector2d>> points; ///< the measured (x, y) points [m] per depth
};

/// meta.json of a record, validated and in SI units.
struct Record {
    std::filesystem::path dir;
    std::string specimen_id;
    double R1 = 0;                 ///< specimen radius D1/2 [m]
    double R2 = 0;                 ///< support-disc radius D2/2 [m]
    double pedestal_height = 0;    ///< [m]
    std::optional<double> areal_density;   ///< [kg/m^2]
    std::optional<double> thickness;       ///< [m]
    std::string colour;                    ///< fabric colour as written by the lab ("" if absent)
    std::map<std::string, Camera> cameras; ///< by station name
    std::vector<Board> boards;
    std::string contours_file = "contours.csv";
    std::vector<double> contour_depths;    ///< declared depths [m]
    double contour_theta_step_deg = 1.0;   ///< angular step of the contour rays [deg]
    double contour_sigma = 0.3e-3;         ///< profiler repeatability, 1 sigma per coordinate [m]
    std::optional<double> lab_drape_coefficient_percent; ///< drapemeter reading [%]
    nlohmann::json raw;                    ///< the whole meta.json, unknown fields included
    std::vector<std::string> unknown_fields; ///< top-level keys this reader does not use (kept in raw)

    std::filesystem::path file(const std::string& name) const { return dir / name; }
    bool has_camera(const std::string& name) const { return cameras.count(name) != 0; }
};

/// Reads and validates RECORD_DIR/meta.json. Throws FileError naming the file,
/// the field (dotted path) and the offending value.
Record read_record(const std::filesystem::path& dir);

/// Parses meta.json text (for tests and tools); `where` names it in messages.
Record parse_meta(const std::string& text, const std::filesystem::path& dir, const std::string& where);

/// Loads the photograph of station `camera` (BGR, 8 bit). Throws FileError when
/// the file is missing, not a decodable image, truncated (no JPEG end marker),
/// or not of the size declared in meta.json.
cv::Mat load_image(const Record& rec, const std::string& camera);

/// Reads the contours CSV named in meta.json. Throws FileError on a missing
/// column, a non-numeric cell (naming line and column) or an empty file.
ContourStack read_contours(const Record& rec);
/// Same from an explicit path with the declared angular step [deg].
ContourStack read_contours_file(const std::filesystem::path& file, double theta_step_deg = 1.0);

} // namespace drape::capture
