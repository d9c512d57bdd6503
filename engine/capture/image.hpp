#pragma once
// The photographs of a record, through OpenCV: loading with the checks a
// received file needs (size declared in meta.json, header read before the
// pixels are decoded, truncated JPEGs refused) and the camera matrix.
#include "engine/record/record.hpp"

#include <opencv2/core.hpp>

#include <filesystem>
#include <string>

namespace drape::capture {

/// The photograph of station `camera` (BGR, 8 bit): JPEG, PNG or BMP. Throws
/// FileError when the file is missing, of another format, not a decodable
/// image, truncated (no JPEG end marker), or not of the size declared in
/// meta.json - the size is read from the file's header before the pixels are
/// decoded (a file whose header gives none is refused), so a header claiming
/// 30000 x 30000 px costs nothing.
cv::Mat load_image(const record::Record& rec, const std::string& camera);

/// A single-camera record's photo `name` (BGR, 8 bit): any size up to 20000 px
/// a side and 200 megapixels (read from the header before decoding), JPEG
/// checked for truncation. Throws FileError.
cv::Mat load_photo(const record::Record& rec, const std::string& name);

/// The same for a photo outside any record (a scale calibration photo), by path.
cv::Mat load_photo_file(const std::filesystem::path& path);

/// The intrinsic matrix K of a camera [px].
cv::Matx33d camera_matrix(const record::Camera& c);

} // namespace drape::capture
