// The photo loader (capture::load_image) through a record in a scratch folder.
// The first four bytes are the size meta.json declares (width, height: 16 bits
// each, 1..4096 px); the rest is the image file. Accepted images have the
// declared size; a header that claims another size is refused before decoding.
#include "engine/capture/image.hpp"
#include "engine/core/error.hpp"
#include "fuzz_common.hpp"

#include <cstdint>

using namespace drape;

DRAPE_FUZZ_TARGET(image)(const std::uint8_t* data, std::size_t size)
{
    if (size < 4) return 0;
    static const std::filesystem::path dir = [] {
        const auto d = fuzz::scratch() / "record";
        std::filesystem::create_directories(d);
        return d;
    }();
    record::Record rec;
    rec.dir = dir;
    record::Camera cam;
    cam.name = "top";
    cam.image = "top.img";
    cam.width = 1 + (data[0] | (data[1] << 8)) % 4096;
    cam.height = 1 + (data[2] | (data[3] << 8)) % 4096;
    cam.fx = cam.fy = 1000;
    rec.cameras["top"] = cam;
    fuzz::write_file(dir / "top.img", reinterpret_cast<const char*>(data + 4), size - 4);
    try {
        const cv::Mat img = capture::load_image(rec, "top");
        fuzz::require(img.cols == cam.width && img.rows == cam.height && img.type() == CV_8UC3, "the image has the declared size");
    } catch (const drape::Error&) {
    }
    return 0;
}
