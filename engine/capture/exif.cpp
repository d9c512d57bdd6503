#include "engine/capture/exif.hpp"

#include "engine/capture/detail/jpeg.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>

namespace drape::capture {

namespace {

/// A TIFF structure inside the EXIF block: byte order and bounds-checked reads.
class Tiff {
public:
    Tiff(const std::uint8_t* p, std::size_t n, bool little) : m_p(p), m_n(n), m_little(little) {}
    bool u16(std::size_t at, std::uint32_t& v) const
    {
        if (at > m_n || m_n - at < 2) return false;
        v = m_little ? (m_p[at] | m_p[at + 1] << 8) : (m_p[at] << 8 | m_p[at + 1]);
        return true;
    }
    bool u32(std::size_t at, std::uint32_t& v) const
    {
        if (at > m_n || m_n - at < 4) return false;
        const std::uint32_t b0 = m_p[at], b1 = m_p[at + 1], b2 = m_p[at + 2], b3 = m_p[at + 3];
        v = m_little ? (b0 | b1 << 8 | b2 << 16 | b3 << 24) : (b0 << 24 | b1 << 16 | b2 << 8 | b3);
        return true;
    }
    /// One IFD's entries: calls f(tag, type, count, value_offset_field_position).
    template <class F> bool entries(std::size_t ifd, F f) const
    {
        std::uint32_t n = 0;
        if (!u16(ifd, n) || n > 1000) return false;
        for (std::uint32_t i = 0; i < n; ++i) {
            const std::size_t e = ifd + 2 + 12 * static_cast<std::size_t>(i);
            std::uint32_t tag = 0, type = 0, count = 0;
            if (!u16(e, tag) || !u16(e + 2, type) || !u32(e + 4, count)) return false;
            f(tag, type, count, e + 8);
        }
        return true;
    }

private:
    const std::uint8_t* m_p;
    std::size_t m_n;
    bool m_little;
};

constexpr std::uint32_t kExifIfdPointer = 0x8769, kFocalLength = 0x920A, kFocalLength35mm = 0xA405;
constexpr std::uint32_t kShort = 3, kLong = 4, kRational = 5;

/// The lens tags of a TIFF block ("II*\0" or "MM\0*" first).
ExifLens read_tiff(const std::uint8_t* p, std::size_t n)
{
    ExifLens out;
    if (n < 8 || !((p[0] == 'I' && p[1] == 'I') || (p[0] == 'M' && p[1] == 'M'))) {
        out.warning = "the EXIF block has no TIFF header";
        return out;
    }
    const Tiff t(p, n, p[0] == 'I');
    std::uint32_t magic = 0, ifd0 = 0;
    if (!t.u16(2, magic) || magic != 42 || !t.u32(4, ifd0)) {
        out.warning = "the EXIF block's TIFF header is malformed";
        return out;
    }
    std::uint32_t exif_ifd = 0;
    if (!t.entries(ifd0, [&](std::uint32_t tag, std::uint32_t type, std::uint32_t, std::size_t at) {
            if (tag == kExifIfdPointer && type == kLong) t.u32(at, exif_ifd);
        })) {
        out.warning = "the EXIF block's first directory runs past its end";
        return out;
    }
    if (exif_ifd == 0) return out; // no EXIF sub-directory: no lens tags
    if (exif_ifd == ifd0) {
        out.warning = "the EXIF block's directories point at each other";
        return out;
    }
    if (!t.entries(exif_ifd, [&](std::uint32_t tag, std::uint32_t type, std::uint32_t count, std::size_t at) {
            if (count < 1) return;
            if (tag == kFocalLength35mm && type == kShort) {
                std::uint32_t v = 0;
                if (t.u16(at, v) && v > 0) out.focal_35mm_mm = v;
            } else if (tag == kFocalLength && type == kRational) {
                std::uint32_t off = 0, num = 0, den = 0;
                if (t.u32(at, off) && t.u32(off, num) && t.u32(off + 4, den) && den > 0 && num > 0)
                    out.focal_mm = static_cast<double>(num) / den;
            }
        }))
        out.warning = "the EXIF block's camera directory runs past its end";
    // Outside any real lens (a 35 mm equivalent of 4-2000 mm): not believed.
    if (out.focal_35mm_mm && !(*out.focal_35mm_mm >= 4 && *out.focal_35mm_mm <= 2000)) out.focal_35mm_mm.reset();
    if (out.focal_mm && !(*out.focal_mm >= 0.5 && *out.focal_mm <= 2000)) out.focal_mm.reset();
    return out;
}

} // namespace

ExifLens exif_lens(const std::vector<std::uint8_t>& b)
{
    if (b.size() < 4 || b[0] != 0xFF || b[1] != 0xD8) return {}; // not a JPEG
    ExifLens out;
    detail::walk_jpeg_segments(b.data(), b.size(), [&](unsigned marker, std::size_t at, std::size_t length) {
        if (length < 2 || at + 2 + length > b.size()) return true; // cut short: no lens
        const std::uint8_t* seg = b.data() + at + 4;
        const std::size_t n = length - 2;
        if (marker != 0xE1 || n < 6 || !std::equal(seg, seg + 6, reinterpret_cast<const std::uint8_t*>("Exif\0\0"))) return false;
        out = read_tiff(seg + 6, n - 6);
        return true;
    }, 64);
    return out;
}

ExifLens exif_lens(const std::filesystem::path& jpeg)
{
    std::ifstream f(jpeg, std::ios::binary);
    if (!f) return {};
    std::vector<std::uint8_t> b(256 * 1024);
    f.read(reinterpret_cast<char*>(b.data()), static_cast<std::streamsize>(b.size()));
    b.resize(static_cast<std::size_t>(std::max<std::streamsize>(0, f.gcount())));
    return exif_lens(b);
}

double focal_px_from_35mm(double f35_mm, int w, int h)
{
    return f35_mm / std::hypot(36.0, 24.0) * std::hypot(static_cast<double>(w), static_cast<double>(h));
}

} // namespace drape::capture
