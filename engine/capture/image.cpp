#include "engine/capture/image.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"

#include <opencv2/imgcodecs.hpp>

#include <optional>
#include <utility>

namespace drape::capture {

namespace {

/// Width and height from a JPEG's SOF marker or a PNG's IHDR; nullopt for
/// other formats (OpenCV then decodes and the size is checked afterwards).
std::optional<std::pair<int, int>> header_size(const std::string& b)
{
    auto u8 = [&](std::size_t i) { return static_cast<unsigned>(static_cast<unsigned char>(b[i])); };
    if (b.size() > 24 && b.compare(0, 8, "\x89PNG\r\n\x1a\n") == 0)
        return std::pair{static_cast<int>((u8(16) << 24) | (u8(17) << 16) | (u8(18) << 8) | u8(19)),
                         static_cast<int>((u8(20) << 24) | (u8(21) << 16) | (u8(22) << 8) | u8(23))};
    if (b.size() < 4 || u8(0) != 0xFF || u8(1) != 0xD8) return std::nullopt;
    std::size_t i = 2;
    while (i + 9 < b.size()) {
        if (u8(i) != 0xFF) return std::nullopt;
        const unsigned marker = u8(i + 1);
        if (marker == 0xD8 || (marker >= 0xD0 && marker <= 0xD7) || marker == 0x01) {
            i += 2;
            continue;
        }
        const std::size_t len = (u8(i + 2) << 8) | u8(i + 3);
        // SOF0..SOF15 except DHT (C4), JPG (C8) and DAC (CC).
        if (marker >= 0xC0 && marker <= 0xCF && marker != 0xC4 && marker != 0xC8 && marker != 0xCC)
            return std::pair{static_cast<int>((u8(i + 7) << 8) | u8(i + 8)), static_cast<int>((u8(i + 5) << 8) | u8(i + 6))};
        if (len < 2) return std::nullopt;
        i += 2 + len;
    }
    return std::nullopt;
}

} // namespace

cv::Mat load_image(const record::Record& rec, const std::string& camera)
{
    auto it = rec.cameras.find(camera);
    if (it == rec.cameras.end())
        throw FileError(rec.dir.string() + "/meta.json: field 'cameras." + camera + "' is missing");
    const record::Camera& cam = it->second;
    const std::string path = rec.file(cam.image).string();
    const std::string bytes = read_file(path, std::size_t(128) << 20);
    if (bytes.empty()) throw FileError(path + ": empty file");
    auto size_mismatch = [&](int w, int h) {
        return FileError(path + ": image is " + std::to_string(w) + " x " + std::to_string(h) +
                         " px but meta.json field 'cameras." + camera + ".width/height' declares " + std::to_string(cam.width) +
                         " x " + std::to_string(cam.height));
    };
    if (const auto wh = header_size(bytes); wh && (wh->first != cam.width || wh->second != cam.height))
        throw size_mismatch(wh->first, wh->second);
    // libjpeg decodes a truncated file with a grey bottom and only a warning;
    // a JPEG must end with the EOI marker FF D9 (trailing padding allowed).
    const bool is_jpeg = bytes.size() > 3 && static_cast<unsigned char>(bytes[0]) == 0xFF && static_cast<unsigned char>(bytes[1]) == 0xD8;
    if (is_jpeg) {
        std::size_t end = bytes.size();
        while (end > 2 && bytes[end - 1] == '\0') --end;
        if (!(static_cast<unsigned char>(bytes[end - 2]) == 0xFF && static_cast<unsigned char>(bytes[end - 1]) == 0xD9))
            throw FileError(path + ": truncated JPEG (no end-of-image marker after " + std::to_string(bytes.size()) + " bytes)");
    }
    const std::vector<unsigned char> buf(bytes.begin(), bytes.end());
    cv::Mat img;
    try {
        img = cv::imdecode(buf, cv::IMREAD_COLOR);
    } catch (const cv::Exception& e) {
        throw FileError(path + ": not a readable image (" + e.what() + ")");
    }
    if (img.empty()) throw FileError(path + ": not a readable image");
    if (img.cols != cam.width || img.rows != cam.height) throw size_mismatch(img.cols, img.rows);
    return img;
}

cv::Mat load_photo(const record::Record& rec, const std::string& name)
{
    const std::string path = rec.file(name).string();
    const std::string bytes = read_file(path, std::size_t(256) << 20);
    if (bytes.empty()) throw FileError(path + ": empty file");
    if (const auto wh = header_size(bytes)) {
        if (wh->first < 16 || wh->second < 16 || wh->first > 20000 || wh->second > 20000 ||
            static_cast<double>(wh->first) * wh->second > 200e6)
            throw FileError(path + ": image is " + std::to_string(wh->first) + " x " + std::to_string(wh->second) +
                            " px (accepted: 16 .. 20000 px a side, at most 200 megapixels)");
    }
    const bool is_jpeg = bytes.size() > 3 && static_cast<unsigned char>(bytes[0]) == 0xFF && static_cast<unsigned char>(bytes[1]) == 0xD8;
    if (is_jpeg) {
        std::size_t end = bytes.size();
        while (end > 2 && bytes[end - 1] == '\0') --end;
        if (!(static_cast<unsigned char>(bytes[end - 2]) == 0xFF && static_cast<unsigned char>(bytes[end - 1]) == 0xD9))
            throw FileError(path + ": truncated JPEG (no end-of-image marker after " + std::to_string(bytes.size()) + " bytes)");
    }
    const std::vector<unsigned char> buf(bytes.begin(), bytes.end());
    cv::Mat img;
    try {
        img = cv::imdecode(buf, cv::IMREAD_COLOR);
    } catch (const cv::Exception& e) {
        throw FileError(path + ": not a readable image (" + e.what() + ")");
    }
    if (img.empty()) throw FileError(path + ": not a readable image");
    return img;
}

cv::Matx33d camera_matrix(const record::Camera& c) { return {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1}; }

} // namespace drape::capture
