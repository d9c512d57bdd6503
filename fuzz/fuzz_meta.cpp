// meta.json of a drape-test record (record::parse_meta) and the paths it names
// (Record::file: contained in the record folder). Bad input must end in a
// drape::Error; what is accepted must lie in its documented ranges.
#include "engine/core/error.hpp"
#include "engine/record/record.hpp"
#include "fuzz_common.hpp"

#include <cmath>
#include <cstdint>

using namespace drape;

DRAPE_FUZZ_TARGET(meta)(const std::uint8_t* data, std::size_t size)
{
    static const std::filesystem::path dir = [] {
        const auto d = fuzz::scratch() / "record";
        std::filesystem::create_directories(d);
        fuzz::write_file(d / "contours.csv", "", 0);
        return d;
    }();
    const std::string text(reinterpret_cast<const char*>(data), size);
    try {
        const record::Record rec = record::parse_meta(text, dir, "meta.json");
        fuzz::require(std::isfinite(rec.R1) && std::isfinite(rec.R2) && rec.R2 > 0 && rec.R2 < rec.R1 && rec.R1 <= 1.0, "specimen and disc radii");
        fuzz::require(rec.pedestal_height > 0 && rec.pedestal_height <= 5, "pedestal height");
        for (double d : rec.contour_depths) fuzz::require(d > 0 && d <= rec.pedestal_height, "declared depth");
        fuzz::require(rec.contour_depths.size() <= 1000, "number of declared depths");
        if (rec.contour_theta_step_deg) fuzz::require(*rec.contour_theta_step_deg >= 0.01 && *rec.contour_theta_step_deg <= 45, "theta step");
        if (rec.lab_drape_coefficient_percent)
            fuzz::require(*rec.lab_drape_coefficient_percent >= 0 && *rec.lab_drape_coefficient_percent <= 100, "lab D");
        for (const auto& [name, c] : rec.cameras) {
            fuzz::require(c.width >= 1 && c.height >= 1 && double(c.width) * c.height <= 150e6, "image size");
            fuzz::require(c.fx >= 1 && c.fx <= 1e6 && c.fy >= 1 && c.fy <= 1e6, "focal lengths");
            fuzz::require(std::isfinite(c.cx) && std::isfinite(c.cy) && c.t.allFinite() && c.R.allFinite(), "finite pose");
            (void)c.project(Eigen::Vector3d(0.1, 0.0, -0.05));
            try {
                const auto p = rec.file(c.image);
                const auto rel = std::filesystem::weakly_canonical(p).lexically_relative(std::filesystem::weakly_canonical(dir));
                fuzz::require(!rel.empty() && *rel.begin() != "..", "an image name leads out of the record");
            } catch (const drape::Error&) {
            }
        }
        try {
            const auto p = rec.file(rec.contours_file);
            const auto rel = std::filesystem::weakly_canonical(p).lexically_relative(std::filesystem::weakly_canonical(dir));
            fuzz::require(!rel.empty() && *rel.begin() != "..", "the contours name leads out of the record");
        } catch (const drape::Error&) {
        }
    } catch (const drape::Error&) {
    }
    return 0;
}
