// Library import (FabricLibrary::import_all / import_preset, as `drape library
// import` calls them) into a library in a scratch folder. What an import
// stores must read back (get, list, export_all); a bad document changes nothing.
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/library/fabric_library.hpp"
#include "fuzz_common.hpp"

#include <cstdint>

using namespace drape;
using namespace drape::library;

DRAPE_FUZZ_TARGET(library)(const std::uint8_t* data, std::size_t size)
{
    static FabricLibrary lib((fuzz::scratch() / "library.sqlite").string());
    static int runs = 0;
    if (++runs % 200 == 0) { // keep the library small: start again now and then
        std::vector<std::string> all;
        for (const auto& r : lib.list()) all.push_back(r.name);
        if (!all.empty()) lib.remove(all);
    }
    const std::string text(reinterpret_cast<const char*>(data), size);
    nlohmann::json doc;
    try {
        doc = parse_json(text, "import.json");
    } catch (const drape::Error&) {
        return 0;
    }
    const int before = lib.count();
    const auto conflict = static_cast<OnConflict>(size % 4);
    std::vector<std::string> stored;
    try {
        if (doc.is_array() || (doc.is_object() && doc.contains("format") && doc["format"] == "drapekit-fabric-library")) {
            stored = lib.import_all(doc, "import.json", conflict).names;
        } else {
            lib.import_preset(doc, "import.json", {}, conflict);
            stored.push_back(fabric::fabric_from_json(doc, "import.json").name);
        }
    } catch (const drape::Error&) {
        fuzz::require(lib.count() == before, "a failed import changed the library");
        return 0;
    }
    for (const auto& n : stored) fuzz::require(lib.find(n).has_value(), "an imported fabric cannot be found by its name");
    try {
        (void)lib.list();
        const nlohmann::json all = lib.export_all();
        (void)all.dump();
    } catch (const std::exception& e) {
        std::fprintf(stderr, "%s\n", e.what());
        fuzz::require(false, "the library does not read back after an import");
    }
    return 0;
}
