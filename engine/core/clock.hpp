#pragma once
// Time stamps written into presets, library rows and exports.
#include <string>

namespace drape {

/// The current time in UTC as ISO 8601 to the second, e.g. "2026-11-29T15:40:00Z".
std::string utc_now();

} // namespace drape
