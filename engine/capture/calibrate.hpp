#pragma once
// Checks a station's declared pose against the chessboards printed on the floor
// sheet: findChessboardCorners on each board's crop, then solvePnP with the
// declared intrinsics over all detected corners.
#include "engine/record/record.hpp"

#include <opencv2/core.hpp>

#include <string>
#include <vector>

namespace drape::capture {

struct Calibration {
    bool ok = false;                 ///< a pose was measured (at least one board detected)
    record::Camera declared;                 ///< as written in meta.json
    record::Camera measured;                 ///< declared intrinsics, pose from solvePnP (= declared when !ok)
    std::vector<std::string> boards_found, boards_missed;
    int corners = 0;                 ///< corners used by solvePnP
    double rms_px_measured = 0;      ///< reprojection RMS of the corners with the measured pose [px]
    double rms_px_declared = 0;      ///< same with the declared pose [px]
    double rotation_diff_deg = 0;    ///< angle of R_measured * R_declared^T [deg]
    double centre_diff_m = 0;        ///< distance between the optical centres [m]
    /// Largest image displacement between the two poses over the specimen's
    /// reach (circle of radius R1 at the pedestal top and 150 mm below) [px].
    double max_shift_px = 0;
    std::vector<std::string> warnings;
};

/// Calibrates station `camera` from `image`. Never throws for a board that is
/// not found (reported in boards_missed); throws ParameterError for an unknown station.
Calibration calibrate_camera(const record::Record& rec, const std::string& camera, const cv::Mat& image);

} // namespace drape::capture
