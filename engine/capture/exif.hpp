#pragma once
// The lens a camera wrote into a JPEG's EXIF block: enough to know a phone
// photo's focal length in pixels without a calibration.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace drape::capture {

/// What a photo's EXIF says about its lens. Every field is optional: most
/// files carry none of them (scans, renders, edited photos).
struct ExifLens {
    std::optional<double> focal_35mm_mm; ///< FocalLengthIn35mmFilm (tag 0xA405) [mm, 35 mm equivalent]
    std::optional<double> focal_mm;      ///< FocalLength (tag 0x920A) [mm, the real lens]
    std::string warning;                 ///< why an EXIF block present was not read ("" when read or absent)
};

/// Reads the lens from the EXIF block (APP1 "Exif") of JPEG bytes. Bounded and
/// defensive: a missing, truncated or malformed block gives an empty result
/// (with `warning` set when a block was there but unreadable), never an error.
ExifLens exif_lens(const std::vector<std::uint8_t>& jpeg);
/// The same from a file (its first 256 KiB); not a JPEG or unreadable: empty.
ExifLens exif_lens(const std::filesystem::path& jpeg);

/// The focal length in pixels of a photo w x h px whose 35 mm equivalent focal
/// length is f35: the equivalent scales the frame's diagonal to 35 mm film's
/// (43.27 mm), so f_px = f35 / 43.27 mm x the diagonal in pixels.
double focal_px_from_35mm(double f35_mm, int w, int h);

} // namespace drape::capture
