#pragma once
// The fabric library's schema: the columns derived from a preset, and the
// migrations that bring an older library file up to date (append, never edit).
#include "engine/fabric/preset.hpp"

#include <cstdint>
#include <optional>
#include <string>

struct sqlite3;

namespace drape::library {

/// The searchable columns of one preset.
struct Columns {
    std::string format, composition;
    double weight = 0;                       ///< [kg/m^2]
    std::optional<double> drape_percent;     ///< D [%]
    std::optional<double> fit_quality;       ///< reduced chi-square
};
Columns derive_columns(const fabric::FabricPreset& p);

/// Brings the open database to `target` (schema version) inside the caller's
/// transaction. Migration i takes the schema from version i to i + 1.
void migrate_schema(sqlite3* db, const std::string& path, std::int64_t from, int target);

} // namespace drape::library
