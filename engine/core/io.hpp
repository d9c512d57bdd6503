#pragma once
// Files in and out, the same way everywhere: whole-file reads with a size
// limit, atomic writes (a failed write never loses the old file) and JSON
// parsing with depth and size limits, all with errors that name the file.
#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>

namespace drape {

/// Largest file read_file() takes by default [bytes]: far above any preset,
/// record or mesh description, far below what would exhaust memory.
inline constexpr std::size_t kMaxReadBytes = std::size_t(256) << 20;
/// Deepest nesting parse_json() accepts: presets and records nest 4-5 levels;
/// a file nested thousands deep is an attack or a corruption, and would
/// overflow the stack when written back.
inline constexpr int kMaxJsonDepth = 64;

/// The whole file. Throws FileError naming the path when it cannot be read, is
/// a folder, or is larger than `max_bytes`.
std::string read_file(const std::string& path, std::size_t max_bytes = kMaxReadBytes);

/// Writes atomically (temporary file + fsync + rename). Throws FileError.
void write_file_atomic(const std::string& path, const std::string& content);

/// Parses JSON text; `where` (usually the path) names it in errors. Throws
/// FileError on a syntax error (with the byte position), on nesting deeper than
/// kMaxJsonDepth, and on numbers outside the double range (1e400).
nlohmann::json parse_json(const std::string& text, const std::string& where);

/// read_file + parse_json.
nlohmann::json read_json_file(const std::string& path);

} // namespace drape
