#include "engine/library/fabric_choices.hpp"

#include "engine/library/fabric_library.hpp"

#include <algorithm>
#include <filesystem>

namespace drape::library {

std::vector<FabricChoice> available_fabrics(const std::string& library_path, const std::string& starter_dir,
                                            std::vector<std::string>* warnings)
{
    namespace fs = std::filesystem;
    std::vector<FabricChoice> out;
    auto warn = [&](const std::string& w) {
        if (warnings) warnings->push_back(w);
    };
    const std::string lib = library_path.empty() ? default_library_path() : library_path;
    std::error_code ec;
    if (fs::exists(lib, ec)) {
        try {
            FabricLibrary L(lib, FabricLibrary::Mode::ReadOnly);
            for (auto& r : L.list()) out.push_back({r.name, "library", r.preset});
        } catch (const std::exception& e) {
            warn(std::string("fabric library: ") + e.what());
        }
    }
    if (!starter_dir.empty() && fs::is_directory(starter_dir, ec)) {
        std::vector<fs::path> files;
        for (const auto& e : fs::directory_iterator(starter_dir, ec))
            if (e.path().extension() == ".json") files.push_back(e.path());
        std::sort(files.begin(), files.end());
        for (const auto& f : files) {
            try {
                fabric::FabricPreset p = fabric::load_fabric(f.string());
                const std::string name = p.name;
                const bool dup = std::any_of(out.begin(), out.end(), [&](const FabricChoice& c) { return c.name == name; });
                if (!dup) out.push_back({name, "starter", std::move(p)});
            } catch (const std::exception& e) {
                warn(e.what());
            }
        }
    }
    try {
        out.push_back({"Seed paper, Table 1", "built-in", fabric::load_fabric("seed-table1")});
    } catch (const std::exception& e) {
        warn(e.what());
    }
    return out;
}

} // namespace drape::library
