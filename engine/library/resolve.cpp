#include "engine/library/resolve.hpp"

#include "engine/core/error.hpp"
#include "engine/library/schema.hpp"
#include "engine/library/starter.hpp"

#include <filesystem>

namespace drape::library {

namespace fs = std::filesystem;

int add_starter_fabrics(FabricLibrary& lib)
{
    nlohmann::json all = nlohmann::json::array();
    for (const auto& s : starters())
        if (!lib.find(s.preset.name)) all.push_back(fabric::fabric_to_json(s.preset));
    if (all.empty()) return 0;
    return lib.import_all(all, "starter fabrics", OnConflict::Skip).added;
}

FabricLibrary open_library(const std::string& path_in, FabricLibrary::Mode mode)
{
    const bool is_default = path_in.empty();
    const std::string path = is_default ? default_library_path() : path_in;
    std::error_code ec;
    if (is_default && !fs::exists(path, ec)) {
        FabricLibrary created(path, FabricLibrary::Mode::ReadWrite);
        add_starter_fabrics(created);
    }
    return FabricLibrary(path, mode);
}

std::optional<FabricRecord> find_fabric(const FabricLibrary& lib, const std::string& name)
{
    if (auto r = lib.find(name)) return r;
    if (auto s = find_starter(name))
        if (auto r = lib.find(s->name)) return r;
    return std::nullopt;
}

FabricRecord library_fabric(const FabricLibrary& lib, const std::string& name)
{
    if (auto r = find_fabric(lib, name)) return std::move(*r);
    const auto s = find_starter(name);
    if (!s) return lib.get(name); // throws NotFoundError naming the library and the name
    const Columns c = derive_columns(*s);
    FabricRecord r;
    r.name = s->name;
    r.composition = c.composition;
    r.format = c.format;
    r.areal_density_kg_m2 = c.weight;
    r.drape_coefficient_percent = c.drape_percent;
    r.fit_quality = c.fit_quality;
    r.revision = 0;
    r.preset = *s;
    r.preset_json = fabric::fabric_to_json(*s);
    return r;
}

fabric::FabricPreset resolve_fabric(const std::string& name, const std::string& library_path)
{
    std::error_code ec;
    if (fs::is_regular_file(name, ec)) return fabric::load_fabric(name);
    if (auto b = fabric::builtin_fabric(name)) return *b;
    const std::string lib_path = library_path.empty() ? default_library_path() : library_path;
    std::string library_note;
    if (fs::exists(lib_path, ec)) {
        try {
            const FabricLibrary lib(lib_path, FabricLibrary::Mode::ReadOnly);
            if (auto r = find_fabric(lib, name)) return r->preset;
            library_note = "not in the fabric library " + lib_path;
        } catch (const FileError& e) {
            library_note = std::string("the fabric library could not be read (") + e.what() + ")";
        }
    } else {
        library_note = "no fabric library at " + lib_path;
    }
    if (auto s = find_starter(name)) return *s;
    const bool looks_like_file = name.find('/') != std::string::npos || (name.size() > 5 && name.ends_with(".json"));
    if (looks_like_file) return fabric::load_fabric(name); // the file error names the path
    std::string shorts;
    for (const auto& s : starters()) shorts += (shorts.empty() ? "" : ", ") + s.short_name;
    throw NotFoundError("fabric '" + name + "': not a preset file, not a built-in (seed-table1), " + library_note +
                        ", not a starter fabric (" + shorts + ")");
}

} // namespace drape::library
