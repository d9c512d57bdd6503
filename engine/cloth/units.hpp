#pragma once
// Unit conversions at the edges. The core works in SI; user-facing strings may
// carry a suffix.
#include <string>

namespace drape {

/// Parses a length such as "300mm", "30 cm", "0.3m" or "0.3" (bare = metres).
/// Returns metres. Throws ParameterError naming `what` and the text on bad input.
double parse_length(const std::string& text, const std::string& what);

/// Formats a double with up to 17 significant digits (round-trips exactly).
std::string format_double(double v);

} // namespace drape
