#pragma once
// The one reader of a drape-test record (shared/data/drape-lab/README.md):
// meta.json (set-up, fabric, cameras, calibration boards, contour
// declarations, lab readings) and the laser contours. Every length read from
// the record (mm) is converted to metres here, at the edge; the rest of the
// code works in SI units in the world frame (origin = centre of the pedestal
// top, z up, x = warp). No OpenCV: the photos themselves are capture's
// business (capture/image.hpp).
//
// A record is a folder a user may have received from someone else: every file
// it names must stay inside it (Record::file refuses "..", absolute paths and
// symbolic links that lead out), and every number is checked against a
// physical range before anything is allocated from it.
#include "engine/cloth/metrics.hpp"

#include <Eigen/Core>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace drape::record {

/// Pinhole camera, OpenCV convention (x right, y down, z forward), world in
/// metres. The projection helpers assume no distortion (the README declares
/// none; capture undistorts images whose coefficients are not zero).
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

/// Laser cross-section contours: one radial profile per depth, increasing depth.
struct ContourStack {
    std::vector<double> depths;                       ///< depth below the pedestal top [m] (> 0)
    std::vector<cloth::RadialProfile> profiles;       ///< r(theta_k) [m], theta_k = 2 pi k / N; NaN where a ray has no point
    std::vector<std::vector<Eigen::Vector2d>> points; ///< the measured (x, y) points [m] per depth
};

/// The flat specimen, centred on the disc (world frame, metres). Round is the
/// lab's case; a rectangle (width along x, length along y before rotation) or
/// any star-shaped polygon around the axis are the others. D of any shape is
/// (A - disc area) / (specimen area - disc area).
struct Specimen {
    enum class Shape { Round, Rectangle, Polygon };
    Shape shape = Shape::Round;
    double radius = 0;                     ///< round [m]
    double width = 0, length = 0;          ///< rectangle: along x, along y before rotation [m]
    double angle = 0;                      ///< rotation about the axis, +x towards +y [rad]
    bool angle_from_photo = false;         ///< "angle_deg": "auto": estimated from the outline
    std::vector<Eigen::Vector2d> polygon;  ///< polygon vertices [m] before rotation (origin = disc centre)

    double area() const;                   ///< flat area [m^2]
    /// Distance from the axis to the flat edge along the ray at theta [rad] [m]
    /// (the outermost crossing for a polygon), with the rotation `angle`.
    double reach(double theta) const;
    double max_reach() const;              ///< largest reach over all angles [m]
    double min_reach() const;              ///< smallest reach [m]
    double equivalent_radius() const;      ///< sqrt(area / pi) [m]: the R1 the round formulas take
    const char* shape_name() const;        ///< "round", "rectangle", "polygon"
    std::string describe() const;          ///< e.g. "rectangle 300 x 400 mm at 0 deg"
};

/// How the scale of a single top photo is known (top_photo.scale.source).
enum class ScaleSource {
    Calibration, ///< cameras.top: a full pinhole calibration (the lab's rig)
    Disc,        ///< the support disc's rim seen in the photo: a circle of known diameter at a known height
    Markers,     ///< printed ArUco markers of known size at a declared height
    Chessboard,  ///< a printed chessboard of known square size at a declared height
    PxPerMm,     ///< a ruler / a known number of pixels per mm at a declared height
};
const char* to_string(ScaleSource s);

/// The single-camera record's top photo (meta.json "top_photo"): a photo and
/// what a lab actually knows about it. Everything optional except the image
/// and the scale source; capture finds the rest in the photo.
struct TopPhoto {
    std::string image;                        ///< file inside the record
    ScaleSource scale = ScaleSource::Disc;
    double reference_height = 0;              ///< z of the scale reference relative to the disc top [m] (floor: -pedestal height)
    std::optional<double> reference_height_sigma; ///< its uncertainty [m] (default: capture's)
    std::optional<double> px_per_mm;          ///< PxPerMm: pixels per mm at reference_height [px/mm]
    std::optional<double> px_per_mm_sigma_rel;///< its relative uncertainty [-]
    // Markers (ArUco).
    std::string marker_dictionary = "DICT_4X4_50";
    double marker_size = 0.05;                ///< black square's edge [m]
    std::map<int, Eigen::Vector2d> marker_layout; ///< optional: marker centre on the sheet by id [m]
    // Chessboard.
    int board_cols = 0, board_rows = 0;       ///< inner corners
    double board_square = 0.025;              ///< [m]
    // Disc position in the photo (optional; else detected).
    std::optional<Eigen::Vector2d> disc_centre_px;
    std::optional<double> disc_radius_px;
    double disc_edge_sigma = 1.0e-3;          ///< where the rim's image edge may lie off the true rim [m]
    // What is known about the camera (optional).
    std::optional<double> camera_height;      ///< optical centre above the disc top [m]
    std::optional<double> camera_height_sigma;///< [m]
    std::optional<double> focal_px;           ///< focal length [px]
    double focal_px_sigma_rel = 0.02;         ///< its relative uncertainty
    std::string focal_px_source = "declared"; ///< where focal_px came from, for the output ("declared", the photo's EXIF)
    std::string perspective = "auto";         ///< none | disc-plane | hem | auto
    // Segmentation overrides.
    std::string mask;                         ///< a user mask image inside the record ("" = none)
    std::string threshold;                    ///< e.g. "L<60" ("" = none)
};

/// meta.json of a record, validated and in SI units.
struct Record {
    std::filesystem::path dir;
    std::string specimen_id;
    double R1 = 0;                 ///< specimen radius D1/2 [m]; the equal-area radius of a non-round specimen
    Specimen specimen;             ///< the flat specimen's shape (round: radius = R1)
    double R2 = 0;                 ///< support-disc radius D2/2 [m]
    double pedestal_height = 0.12; ///< [m]
    std::optional<double> areal_density;   ///< [kg/m^2]
    std::optional<double> thickness;       ///< [m]
    std::string colour;                    ///< fabric colour as written by the lab ("" if absent)
    std::map<std::string, Camera> cameras; ///< by station name
    std::vector<Board> boards;
    std::string contours_file = "contours.csv";
    std::vector<double> contour_depths;    ///< declared depths [m]
    std::optional<double> contour_theta_step_deg; ///< declared angular step of the contour rays [deg]
    double contour_sigma = 0.3e-3;         ///< profiler repeatability, 1 sigma per coordinate [m]
    std::optional<double> lab_drape_coefficient_percent; ///< drapemeter reading [%]
    std::optional<int> node_count;         ///< folds, when the lab states them
    std::optional<TopPhoto> top_photo;     ///< a single-camera record's photo (meta.json "top_photo")
    nlohmann::json raw;                    ///< the whole meta.json, unknown fields included
    std::vector<std::string> unknown_fields; ///< top-level keys this reader does not use (kept in raw)

    /// A file the record names, resolved inside the record folder. Throws
    /// FileError when the name is absolute, climbs out with "..", or leads out
    /// of the folder through a symbolic link.
    std::filesystem::path file(const std::string& name) const;
    bool has_camera(const std::string& name) const { return cameras.count(name) != 0; }
    /// True when the contours file exists in the record.
    bool has_contours() const;
    /// True for a single-camera record whose scale does not come from cameras.top.
    bool single_camera() const { return top_photo && top_photo->scale != ScaleSource::Calibration; }
    /// The top photo's file name (top_photo.image, else cameras.top.image; "" when neither).
    std::string top_image() const;
};

/// Reads and validates RECORD_DIR/meta.json. Throws FileError naming the file,
/// the field (dotted path) and the offending value.
Record read_record(const std::filesystem::path& dir);

/// Parses meta.json text (for tests and tools); `where` names it in messages.
Record parse_meta(const std::string& text, const std::filesystem::path& dir, const std::string& where);
/// The same from a parsed document (what `drape measure --top` builds from its flags).
Record parse_meta_json(const nlohmann::json& root, const std::filesystem::path& dir, const std::string& where);

/// Reads the contours CSV named in meta.json (header depth_mm,theta_deg,x_mm,y_mm
/// in any column order). Throws FileError naming the line and column on a
/// missing column, a cell that is not exactly a number, an angle off the ray
/// grid or repeated, a depth outside the pedestal, or a radius the specimen
/// cannot reach. Missing rays are NaN in the profile (a depth is then not complete()).
ContourStack read_contours(const Record& rec);
/// The same from an explicit file; `R1`, `R2`, `pedestal_height` bound the values [m];
/// `theta_step_deg` (0 = infer from the data) is the ray spacing.
ContourStack read_contours_file(const std::filesystem::path& file, double theta_step_deg, double R1, double R2,
                                double pedestal_height);
/// The same from the file's text (tests and the fuzzer); `where` names it in messages.
ContourStack parse_contours(const std::string& text, const std::string& where, double theta_step_deg, double R1, double R2,
                            double pedestal_height);
/// The farthest a contour point may lie from the axis, as a multiple of the
/// specimen's reach: a drape hangs inside its own radius (set-a and set-d: at
/// most 0.99 of it), so 1.2 leaves room for a specimen laid a fifth of its
/// radius off centre; a point beyond it is a wrong unit or a broken file.
inline constexpr double kMaxContourReach = 1.2;
/// True for a contours file without data: empty, blank, or its header line
/// only (a lab without a laser profiler, or one that cut no depth: set-d's
/// DL-D3-240-180). Such a record has no contours; it is not a bad file. A file
/// that cannot be read, or is larger than read_contours takes, is false (the
/// reader then says why).
bool no_contour_rows(const std::filesystem::path& file);
/// Largest contours.csv read [bytes].
inline constexpr std::size_t kMaxContoursBytes = std::size_t(64) << 20;

} // namespace drape::record
