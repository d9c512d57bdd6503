#pragma once
// From a drape-lab record to calibrated measurements: top-view segmentation,
// perspective-corrected shadow outline -> shared drape metrics, side-view hem,
// laser-contour Fourier series. Everything in metres, world frame. Each step
// lives in its own file (segmentation, top_view, side_view, contour_levels);
// report.hpp writes the JSON and the overlay, kes.hpp the KES regression.
#include "engine/capture/calibrate.hpp"
#include "engine/capture/contour_levels.hpp"
#include "engine/capture/kes.hpp"
#include "engine/capture/segmentation.hpp"
#include "engine/capture/side_view.hpp"
#include "engine/capture/top_view.hpp"
#include "engine/record/record.hpp"

#include <opencv2/core.hpp>

#include <optional>
#include <string>
#include <vector>

namespace drape::capture {

struct Measurement {
    std::string specimen_id;
    /// Set when the top view was refused: a check failed (which, why, what to
    /// try). Then there is no drape coefficient, never a number.
    std::optional<Refusal> refused;
    /// The top camera used and what is known about it (scale source, camera
    /// height, disc rim, markers); set once the top photo is read.
    std::optional<ViewGeometry> view;
    std::optional<double> lab_dc_percent;
    std::optional<Calibration> top_calibration;
    TopView top;
    SideView side;
    std::vector<ContourLevel> contours;
    std::optional<double> hem_min_height;  ///< lowest hem point z [m] (< 0 below the pedestal top)
    /// The bending rigidity [N*m] whose free radial strips (heavy elastica clamped
    /// level at the rim, cloth/elastica.hpp) drape to the measured D: a fabric of
    /// one linear bending that drapes to that D has at most this bending. Round
    /// specimens with a declared areal density only.
    std::optional<double> free_strip_bending_bound;
    std::string hem_min_source;            ///< which evidence gave it
    std::vector<std::string> measured;     ///< what was measured
    std::vector<std::string> not_measured; ///< "what: why"
    /// Files the record names that are there but could not be read (a value out
    /// of range, a cell that is not a number, a photo that is not what
    /// meta.json says): each error as the reader gave it (file, line, field,
    /// value). Also in not_measured; `drape measure` exits 1 on any (bad input),
    /// after printing what it did measure.
    std::vector<std::string> bad_files;
    std::vector<std::string> warnings;
    cv::Mat top_image, side_image;         ///< kept for overlays (empty when absent)
};

struct MeasureOptions {
    int rays = 720;                 ///< rays traced around the axis for the outline
    bool calibrate = true;          ///< measure the top pose from the chessboards
    /// Node detection etc. (the shared defaults of cloth::MetricOptions). A crest
    /// counts as a node when it rises 10 % of the outline's radial range above
    /// both neighbouring troughs: on the set-a overlays 0.05 to 0.10 all give the
    /// counts a person makes by eye, 0.15 drops the weak folds of DL-A01 and DL-A10.
    cloth::MetricOptions metrics;
    /// Perspective model of the reported D: "auto" (hem when the camera height
    /// is known, else disc-plane; a record's top_photo.perspective), "none",
    /// "disc-plane", "hem", "calibration" (hem on a calibrated camera).
    std::string perspective = "auto";
    /// "auto" (the lab classifier for calibrated records, the photo segmenter
    /// for single photos), "photo" (the photo segmenter for any record), "lab"
    /// (the lab classifier for any record: fabric colour on the disc against
    /// a floor ring beyond the specimen, by chroma or darkness).
    std::string segmentation = "auto";
    /// Manual overrides (threshold, user mask); they select the photo segmenter.
    SegmentOverrides overrides;
    /// A single photo's markers or chessboard as found once in a separate
    /// calibration photo of the same fixed camera (read_scale_calibration): not
    /// searched in the photo. Only for single-camera records.
    std::optional<ScaleCalibration> scale_calibration;
};

/// Segments and measures a record. Missing or broken optional files
/// (photos, contours) are listed in not_measured (the broken ones in
/// bad_files too); a broken meta.json throws.
Measurement measure_record(const record::Record& rec, const MeasureOptions& opt = {});

/// The pedestal's diameter from the record's side photo alone (what
/// measure_record reports as side.pedestal), without the top view's work; not
/// measured when there is no side camera or photo, or it cannot be read.
PedestalWidth measure_pedestal_width(const record::Record& rec);

} // namespace drape::capture
