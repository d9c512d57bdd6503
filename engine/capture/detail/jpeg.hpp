#pragma once
// A JPEG's marker segments, walked without decoding: the photo reader finds the
// frame header (its size) and the EXIF reader the APP1 block the same way.
// Internal to engine/capture (not installed).
#include <cstddef>

namespace drape::capture::detail {

/// Walks the marker segments of JPEG bytes `b` (n of them, SOI first) up to the
/// image data: calls visit(marker, at, length) for each segment that has a length
/// field (`at`: the segment's 0xFF; `length`: the field's value, which counts its
/// own two bytes and may run past n - the caller checks what it reads) and
/// returns true as soon as visit does. Fill bytes, SOI, RSTn and TEM carry no
/// length and are stepped over. False when the bytes stop being markers, the
/// image data (SOS) or the end (EOI) comes first, a length field is cut off, a
/// length is below 2, or `max_steps` markers (fill bytes included) were read.
template <class Visit>
bool walk_jpeg_segments(const unsigned char* b, std::size_t n, Visit visit, std::size_t max_steps = static_cast<std::size_t>(-1))
{
    std::size_t i = 2;
    for (std::size_t step = 0; step < max_steps && i + 1 < n; ++step) {
        if (b[i] != 0xFF) return false;
        const unsigned marker = b[i + 1];
        if (marker == 0xFF) { // fill byte
            ++i;
            continue;
        }
        if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {
            i += 2;
            continue;
        }
        if (marker == 0xDA || marker == 0xD9) return false; // image data, or the end
        if (i + 3 >= n) return false;
        const std::size_t length = static_cast<std::size_t>(b[i + 2]) << 8 | b[i + 3];
        if (visit(marker, i, length)) return true;
        if (length < 2) return false;
        i += 2 + length;
    }
    return false;
}

} // namespace drape::capture::detail
