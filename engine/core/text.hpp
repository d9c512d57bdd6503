#pragma once
// Text that comes from users and files: UTF-8 validity, Unicode NFC, names a
// person can tell apart, and echoing untrusted text in messages without
// letting it reach the terminal raw (control characters, broken UTF-8).
#include <cstddef>
#include <optional>
#include <string>
#include <string_view>

namespace drape {

/// True when `s` is well-formed UTF-8 (no overlong forms, no surrogates,
/// nothing above U+10FFFF).
bool is_valid_utf8(std::string_view s);

/// Offset of the first byte that does not start a well-formed UTF-8 sequence,
/// std::string_view::npos when `s` is valid UTF-8.
std::size_t first_invalid_utf8(std::string_view s);

/// Number of code points of valid UTF-8 text.
std::size_t utf8_length(std::string_view s);

/// Unicode Normalization Form C of valid UTF-8 text (tables generated from the
/// Unicode version unicode_version() names). "Cafe" + U+0301 becomes "Café"
/// (U+00E9): the same name however a keyboard or a file system spelled it.
/// Throws ParameterError when `s` is not valid UTF-8.
std::string to_nfc(std::string_view s);
const char* unicode_version();

/// A name as stored and looked up (fabric names): NFC, without leading and
/// trailing white space (Unicode White_Space, also U+00A0 no-break space,
/// U+200B zero-width space and U+FEFF), 1..max_chars characters, without
/// control characters, line or paragraph separators or bidirectional
/// overrides. Throws ParameterError naming `what` and the name on bad input.
std::string normalize_name(std::string_view name, const std::string& what, std::size_t max_chars = 200);
/// The same, nullopt instead of throwing.
std::optional<std::string> try_normalize_name(std::string_view name, std::size_t max_chars = 200);

/// Untrusted text for a message: control characters and bytes that are not
/// UTF-8 written as \xNN (newline and tab as \n and \t), cut after
/// `max_chars` characters with "...". Never throws.
std::string printable(std::string_view s, std::size_t max_chars = 120);

/// `s` with the ASCII letters A-Z lowered (file extensions, keywords); other bytes as they are.
std::string ascii_lower(std::string_view s);

/// `s` without the blanks (spaces and tabs) at either end.
std::string trim_blanks(std::string_view s);

} // namespace drape
