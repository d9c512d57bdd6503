#pragma once
// `drape measure --batch FOLDER --manifest M.csv`: per-photo set-up values for a
// batch of single photos (disc and specimen sizes, a rectangle's orientation,
// the disc centre), read and checked in full before any photo is measured.
// Empty cells, and photos the manifest does not list, take the command line's
// (or the --meta template's) values.
#include <optional>
#include <string>
#include <vector>

namespace drape::cli {

/// One photo's row of a manifest.
struct ManifestRow {
    std::string photo;                       ///< file name inside the batch folder
    int line = 0;                            ///< line in the manifest file (the header is line 1)
    std::optional<double> disc_mm;           ///< support disc diameter [mm]
    std::optional<double> specimen_width_mm; ///< a round specimen's diameter, or a rectangle's width [mm]
    std::optional<double> specimen_length_mm;///< a rectangle's length [mm] (given as WxL)
    std::optional<double> specimen_angle_deg;///< a rectangle's rotation from the photo's x axis [deg]
    bool specimen_angle_auto = false;        ///< specimen_angle_deg = auto: from the outline
    std::string specimen_angle_text;         ///< the cell as written (for messages)
    std::optional<double> centre_x_px, centre_y_px; ///< the disc centre in the photo [px] (both or neither)
};

struct PhotoManifest {
    std::string file;                  ///< the manifest's path, as given
    std::vector<std::string> columns;  ///< its header
    std::vector<ManifestRow> rows;
    /// The row of a photo (by file name), or nullptr.
    const ManifestRow* find(const std::string& photo) const;
    /// "M.csv:LINE" for messages.
    std::string where(const ManifestRow& r) const;
};

/// The columns a manifest may have (`photo` is required).
const std::vector<std::string>& manifest_columns();

/// Reads and checks a manifest: a header naming known columns, one row per
/// photo of `photos` (the file names the batch measures inside `folder`; a row
/// naming another file is an error), numbers where numbers belong, no photo
/// twice. Throws FileError naming the file, line, column and value.
PhotoManifest read_photo_manifest(const std::string& path, const std::string& folder, const std::vector<std::string>& photos);

} // namespace drape::cli
