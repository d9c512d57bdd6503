#pragma once
// Unit conversions and number formatting at the edges. The core works in SI;
// user-facing strings may carry a suffix.
#include <string>
#include <string_view>

namespace drape {

/// Parses a length such as "300mm", "30 cm", "0.3m" or "0.3" (bare = metres).
/// Returns metres. Throws ParameterError naming `what` and the text on bad input.
double parse_length(const std::string& text, const std::string& what);

/// Strict number parsing: the whole text (surrounding blanks allowed) must be
/// one finite decimal number ("81.5abc", "", "nan", "1e400" are refused).
/// Returns false instead of throwing; callers name the file, line and field.
bool parse_number(std::string_view text, double& out);

/// Formats a double with up to 17 significant digits (round-trips exactly).
std::string format_double(double v);

/// Formats a double for a message: up to 6 significant digits (0.08 prints as
/// 0.08, not 0.080000000000000002). For values a person reads, not for files.
std::string format_value(double v);

} // namespace drape
