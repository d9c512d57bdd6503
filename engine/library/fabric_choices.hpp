#pragma once
// The fabrics a user can pick from: the fabric library, then the starter
// presets shipped with Drapekit, then the built-in seed preset.
#include "engine/fabric/preset.hpp"

#include <string>
#include <vector>

namespace drape::library {

/// Fabric choices: the user's library (engine/library), then the starter
/// presets shipped in data/library, then the built-in seed Table 1 preset.
struct FabricChoice {
    std::string name;   ///< display name
    std::string origin; ///< "library", "starter", "built-in", "fitted"
    fabric::FabricPreset preset;
};
/// `library_path` empty = the default library; a missing library is skipped.
/// Never throws: unreadable entries are left out and reported in `warnings`.
std::vector<FabricChoice> available_fabrics(const std::string& library_path, const std::string& starter_dir,
                                            std::vector<std::string>* warnings = nullptr);

} // namespace drape::library
