// contours.csv (record::parse_contours). The first byte picks the declared ray
// step (0 = inferred from the angles); the rest is the file. Accepted stacks
// hold only values in the reader's documented ranges.
#include "engine/core/error.hpp"
#include "engine/record/record.hpp"
#include "fuzz_common.hpp"

#include <cmath>
#include <cstdint>

using namespace drape;

DRAPE_FUZZ_TARGET(contours)(const std::uint8_t* data, std::size_t size)
{
    if (size < 1) return 0;
    static const double kSteps[] = {0, 1, 10, 0.5, 0.01, 5, 2, 0.25};
    const double step = kSteps[data[0] % 8];
    const std::string text(reinterpret_cast<const char*>(data + 1), size - 1);
    const double R1 = 0.15, R2 = 0.075, H = 0.12;
    try {
        const record::ContourStack st = record::parse_contours(text, "contours.csv", step, R1, R2, H);
        fuzz::require(st.depths.size() == st.profiles.size() && st.depths.size() == st.points.size(), "one profile per depth");
        fuzz::require(!st.depths.empty() && st.depths.size() <= 1000, "number of depths");
        for (std::size_t d = 0; d < st.depths.size(); ++d) {
            fuzz::require(st.depths[d] > 0 && st.depths[d] <= H + 1e-12, "depth range");
            if (d > 0) fuzz::require(st.depths[d] > st.depths[d - 1], "depths increase");
            const auto& r = st.profiles[d].r;
            fuzz::require(r.size() >= 8 && r.size() <= 36000, "rays per depth");
            for (double x : r) fuzz::require(std::isnan(x) || (x >= 0.5 * R2 - 1e-12 && x <= record::kMaxContourReach * R1 + 1e-12), "radius range");
        }
    } catch (const drape::Error&) {
    }
    return 0;
}
