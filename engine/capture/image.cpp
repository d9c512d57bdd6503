#include "engine/capture/image.hpp"

#include "engine/capture/detail/jpeg.hpp"
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"

#include <opencv2/imgcodecs.hpp>

#include <cstdint>
#include <optional>
#include <utility>

namespace drape::capture {

namespace {

enum class Format { Jpeg, Png, Bmp, Other };

Format format_of(const std::string& b)
{
    if (b.size() >= 3 && static_cast<unsigned char>(b[0]) == 0xFF && static_cast<unsigned char>(b[1]) == 0xD8 &&
        static_cast<unsigned char>(b[2]) == 0xFF)
        return Format::Jpeg;
    if (b.size() >= 8 && b.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0) return Format::Png;
    if (b.size() >= 2 && b[0] == 'B' && b[1] == 'M') return Format::Bmp;
    return Format::Other;
}

/// Width and height from a JPEG's frame header (SOF), a PNG's IHDR or a BMP's
/// info header: read before any pixel is decoded. nullopt when the header is
/// not there (the file is then refused: decoding it would allocate whatever
/// size the decoder finds later).
std::optional<std::pair<long, long>> header_size(const std::string& b, Format f)
{
    auto u8 = [&](std::size_t i) { return static_cast<unsigned long>(static_cast<unsigned char>(b[i])); };
    switch (f) {
    case Format::Png:
        if (b.size() < 24 || b.compare(12, 4, "IHDR") != 0) return std::nullopt;
        return std::pair{static_cast<long>((u8(16) << 24) | (u8(17) << 16) | (u8(18) << 8) | u8(19)),
                         static_cast<long>((u8(20) << 24) | (u8(21) << 16) | (u8(22) << 8) | u8(23))};
    case Format::Bmp: {
        if (b.size() < 26) return std::nullopt;
        const auto le32 = [&](std::size_t i) {
            return static_cast<std::int32_t>(static_cast<std::uint32_t>(u8(i) | (u8(i + 1) << 8) | (u8(i + 2) << 16) | (u8(i + 3) << 24)));
        };
        const std::int32_t w = le32(18), h = le32(22); // a negative height: rows stored top-down
        return std::pair{static_cast<long>(w), h < 0 ? -static_cast<long>(h) : static_cast<long>(h)};
    }
    case Format::Jpeg: {
        std::optional<std::pair<long, long>> size;
        detail::walk_jpeg_segments(reinterpret_cast<const unsigned char*>(b.data()), b.size(), [&](unsigned marker, std::size_t i, std::size_t) {
            // SOF0..SOF15 except DHT (C4), JPG (C8) and DAC (CC).
            if (!(marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC)) return false;
            if (i + 8 < b.size()) size = std::pair{static_cast<long>((u8(i + 7) << 8) | u8(i + 8)), static_cast<long>((u8(i + 5) << 8) | u8(i + 6))};
            return true;
        });
        return size; // none before the image data (or the end): refused
    }
    case Format::Other: break;
    }
    return std::nullopt;
}

/// A photo's bytes with its format and the size its header declares, read
/// before any pixel is decoded (decoding allocates whatever size it finds).
struct PhotoFile {
    std::string path, bytes;
    Format format = Format::Other;
    long width = 0, height = 0;
};

PhotoFile read_photo(const std::string& path, std::size_t limit)
{
    PhotoFile f{path, read_file(path, limit)};
    if (f.bytes.empty()) throw FileError(path + ": empty file");
    f.format = format_of(f.bytes);
    if (f.format == Format::Other)
        throw FileError(path + ": not a JPEG, PNG or BMP image (the formats whose size is read before the pixels are decoded)");
    const auto wh = header_size(f.bytes, f.format);
    if (!wh) throw FileError(path + ": no image size in the file's header (a damaged or truncated image)");
    f.width = wh->first;
    f.height = wh->second;
    return f;
}

cv::Mat decode(const PhotoFile& f)
{
    // libjpeg decodes a truncated file with a grey bottom and only a warning;
    // a JPEG must end with the EOI marker FF D9 (trailing padding allowed).
    if (f.format == Format::Jpeg) {
        std::size_t end = f.bytes.size();
        while (end > 2 && f.bytes[end - 1] == '\0') --end;
        if (!(static_cast<unsigned char>(f.bytes[end - 2]) == 0xFF && static_cast<unsigned char>(f.bytes[end - 1]) == 0xD9))
            throw FileError(f.path + ": truncated JPEG (no end-of-image marker after " + std::to_string(f.bytes.size()) + " bytes)");
    }
    const std::vector<unsigned char> buf(f.bytes.begin(), f.bytes.end());
    cv::Mat img;
    try {
        img = cv::imdecode(buf, cv::IMREAD_COLOR);
    } catch (const cv::Exception& e) {
        throw FileError(f.path + ": not a readable image (" + e.what() + ")");
    }
    if (img.empty()) throw FileError(f.path + ": not a readable image");
    return img;
}

} // namespace

cv::Mat load_image(const record::Record& rec, const std::string& camera)
{
    auto it = rec.cameras.find(camera);
    if (it == rec.cameras.end())
        throw FileError(rec.dir.string() + "/meta.json: field 'cameras." + camera + "' is missing");
    const record::Camera& cam = it->second;
    const PhotoFile f = read_photo(rec.file(cam.image).string(), std::size_t(128) << 20);
    auto size_mismatch = [&](long w, long h) {
        return FileError(f.path + ": image is " + std::to_string(w) + " x " + std::to_string(h) +
                         " px but meta.json field 'cameras." + camera + ".width/height' declares " + std::to_string(cam.width) +
                         " x " + std::to_string(cam.height));
    };
    if (f.width != cam.width || f.height != cam.height) throw size_mismatch(f.width, f.height);
    const cv::Mat img = decode(f);
    if (img.cols != cam.width || img.rows != cam.height) throw size_mismatch(img.cols, img.rows);
    return img;
}

cv::Mat load_photo(const record::Record& rec, const std::string& name) { return load_photo_file(rec.file(name)); }

cv::Mat load_photo_file(const std::filesystem::path& path)
{
    const PhotoFile f = read_photo(path.string(), std::size_t(256) << 20);
    if (f.width < 16 || f.height < 16 || f.width > 20000 || f.height > 20000 || static_cast<double>(f.width) * f.height > 200e6)
        throw FileError(f.path + ": image is " + std::to_string(f.width) + " x " + std::to_string(f.height) +
                        " px (accepted: 16 .. 20000 px a side, at most 200 megapixels)");
    return decode(f);
}

cv::Matx33d camera_matrix(const record::Camera& c) { return {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1}; }

} // namespace drape::capture
