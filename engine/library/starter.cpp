#include "engine/library/starter.hpp"

#include "engine/core/io.hpp"
#include "engine/core/text.hpp"

#include <algorithm>
#include <cctype>

namespace drape::library {


const std::vector<Starter>& starters()
{
    static const std::vector<Starter> all = [] {
        std::vector<Starter> out;
        for (const auto& f : starter_files()) {
            const std::string stem = f.stem;
            const std::string where = "starter fabric " + stem + ".json";
            Starter s;
            s.short_name = stem.substr(0, stem.find('-'));
            s.preset = fabric::fabric_from_json(parse_json(f.json, where), where);
            out.push_back(std::move(s));
        }
        return out;
    }();
    return all;
}

std::optional<fabric::FabricPreset> find_starter(const std::string& name)
{
    const std::string n = ascii_lower(name);
    for (const auto& s : starters())
        if (s.short_name == n || ascii_lower(s.preset.name) == n) return s.preset;
    return std::nullopt;
}

} // namespace drape::library
