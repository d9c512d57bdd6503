#include "engine/library/starter.hpp"

#include "engine/core/io.hpp"

#include <algorithm>
#include <cctype>

namespace drape::library {

namespace {
std::string lower(std::string s)
{
    std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    return s;
}
} // namespace

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
    const std::string n = lower(name);
    for (const auto& s : starters())
        if (s.short_name == n || lower(s.preset.name) == n) return s.preset;
    return std::nullopt;
}

} // namespace drape::library
