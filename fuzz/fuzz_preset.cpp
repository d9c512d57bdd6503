// Preset JSON in both formats (drapekit-fabric and seed-19): parse_json with
// its limits, fabric_from_json, and the round trip a library relies on - a
// preset that was read is written and must read back to the same values.
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/fabric/preset.hpp"
#include "fuzz_common.hpp"

#include <cmath>
#include <cstdint>

using namespace drape;

DRAPE_FUZZ_TARGET(preset)(const std::uint8_t* data, std::size_t size)
{
    const std::string text(reinterpret_cast<const char*>(data), size);
    fabric::FabricPreset p;
    try {
        p = fabric::fabric_from_json(parse_json(text, "preset.json"), "preset.json");
    } catch (const drape::Error&) {
        return 0;
    }
    for (const auto& sp : cloth::param_table())
        fuzz::require(std::isfinite(p.params[sp.id]) && p.params[sp.id] >= sp.lower && p.params[sp.id] <= sp.upper, "parameter in the table's range");
    if (p.drape) fuzz::require(p.drape->percent >= 0 && p.drape->percent <= 100, "D in percent");
    (void)p.material(); // what the engine drapes: grid springs of a seed preset
    std::string written;
    try {
        written = fabric::fabric_to_json(p).dump(2);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        fuzz::require(false, "a preset that was read cannot be written");
    }
    try {
        const fabric::FabricPreset again = fabric::fabric_from_json(parse_json(written, "written"), "written");
        for (const auto& sp : cloth::param_table()) fuzz::require(again.params[sp.id] == p.params[sp.id], "round trip keeps the parameters");
        fuzz::require(again.is_seed() == p.is_seed() && again.name == p.name, "round trip keeps the kind and name");
    } catch (const drape::Error& e) {
        std::fprintf(stderr, "%s\n", e.what());
        fuzz::require(false, "a preset that was read and written does not read back");
    }
    return 0;
}
