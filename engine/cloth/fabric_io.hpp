#pragma once
// Fabric preset files (JSON). Two formats:
//  - "drapekit-fabric" v1: continuum SI parameters keyed by the parameter
//    table's keys (units in the key names), plus name, model options,
//    provenance and fit data kept verbatim;
//  - "seed-19": the seed paper's 19 grid constants (seed_format.hpp), exact.
// `seed-table1` names the built-in Table 1 preset.
#include "drape.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace drape::cloth {

struct FabricPreset {
    FabricSpec fabric;
    ModelOptions model;
    nlohmann::json extra = nlohmann::json::object(); ///< provenance, fit, unknown fields: kept, written back
};

/// Reads a preset file or a built-in name ("seed-table1"). Throws FileError /
/// ParameterError naming the file, field and value.
FabricPreset load_fabric(const std::string& path_or_name);
FabricPreset fabric_from_json(const nlohmann::json& j, const std::string& where);
nlohmann::json fabric_to_json(const FabricPreset& p);
/// Writes atomically (temporary file + rename) so a failed write never loses the old file.
void save_fabric(const FabricPreset& p, const std::string& path);

nlohmann::json seed_to_json(const SeedParams& s);
SeedParams seed_from_json(const nlohmann::json& j, const std::string& where);

/// Atomic text write helper (temp + fsync + rename). Throws FileError.
void write_file_atomic(const std::string& path, const std::string& content);
std::string read_file(const std::string& path); ///< throws FileError naming the path

} // namespace drape::cloth
