#include "engine/core/io.hpp"

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <fcntl.h>
#include <unistd.h>

namespace drape {

using nlohmann::json;

std::string read_file(const std::string& path, std::size_t max_bytes)
{
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) throw FileError(path + ": is a folder, not a file");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FileError(path + ": cannot open file for reading");
    in.seekg(0, std::ios::end);
    const std::streamoff size = in.tellg();
    in.seekg(0, std::ios::beg);
    if (size > 0 && static_cast<std::size_t>(size) > max_bytes)
        throw FileError(path + ": file is " + std::to_string(size) + " bytes, more than the " + std::to_string(max_bytes) +
                        " this reader takes");
    std::ostringstream ss;
    ss << in.rdbuf();
    if (in.bad()) throw FileError(path + ": read error");
    return ss.str();
}

void write_file_atomic(const std::string& path, const std::string& content)
{
    const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
    const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (fd < 0) throw FileError(path + ": cannot create temporary file " + tmp);
    std::size_t done = 0;
    while (done < content.size()) {
        const ssize_t w = ::write(fd, content.data() + done, content.size() - done);
        if (w <= 0) {
            ::close(fd);
            ::unlink(tmp.c_str());
            throw FileError(path + ": write failed (disk full?); the previous file is unchanged");
        }
        done += static_cast<std::size_t>(w);
    }
    if (::fsync(fd) != 0 || ::close(fd) != 0) {
        ::unlink(tmp.c_str());
        throw FileError(path + ": could not flush to disk; the previous file is unchanged");
    }
    if (std::rename(tmp.c_str(), path.c_str()) != 0) {
        ::unlink(tmp.c_str());
        throw FileError(path + ": could not replace the file");
    }
}

json parse_json(const std::string& text, const std::string& where)
{
    // The callback sees every value with its depth, before the value is
    // stored: a too-deep document is refused while it is parsed, so it never
    // exists in memory (destroying or dumping it would recurse that deep).
    const json::parser_callback_t limit = [&](int depth, json::parse_event_t event, json& parsed) {
        if (depth > kMaxJsonDepth)
            throw FileError(where + ": JSON nested deeper than " + std::to_string(kMaxJsonDepth) + " levels");
        if (event == json::parse_event_t::value && parsed.is_number_float() && !std::isfinite(parsed.get<double>()))
            throw FileError(where + ": a number is outside the range of a double (e.g. 1e400)");
        return true;
    };
    try {
        return json::parse(text, limit);
    } catch (const json::parse_error& e) {
        // The message quotes what was last read: raw bytes of the file.
        throw FileError(where + ": not valid JSON (" + printable(e.what(), 300) + ")");
    } catch (const json::out_of_range& e) {
        throw FileError(where + ": a number in the JSON is out of range (" + printable(e.what(), 300) + ")");
    }
}

json read_json_file(const std::string& path) { return parse_json(read_file(path), path); }

} // namespace drape
