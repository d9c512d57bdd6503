#pragma once
// The starter fabrics Drapekit ships (data/library/*.json, embedded in the
// build): class presets of silk, cotton, wool and denim, so a brand-new user
// has fabrics to drape and a first library to start from.
#include "engine/fabric/preset.hpp"

#include <optional>
#include <string>
#include <vector>

namespace drape::library {

struct StarterFile {
    const char* stem; ///< file name without .json, e.g. "cotton-plain-weave"
    const char* json; ///< the file's text
};
/// The embedded files, sorted by stem (generated at build time).
const std::vector<StarterFile>& starter_files();

struct Starter {
    std::string short_name;     ///< the first word of the file name: silk, cotton, wool, denim
    fabric::FabricPreset preset; ///< with its full name, e.g. "Silk (class preset)"
};
/// The starter presets, parsed (once).
const std::vector<Starter>& starters();
/// A starter by short name or full name (case-insensitive); nullopt otherwise.
std::optional<fabric::FabricPreset> find_starter(const std::string& name);

} // namespace drape::library
