#include "engine/core/io.hpp"

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"

#include <algorithm>
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
        // nlohmann names the number but not where it is: find it (the first
        // occurrence of that text) for the line and column.
        const std::string msg = e.what();
        std::string at;
        const auto q1 = msg.find('\''), q2 = msg.rfind('\'');
        if (q1 != std::string::npos && q2 > q1 + 1) {
            const std::string number = msg.substr(q1 + 1, q2 - q1 - 1);
            if (const auto pos = text.find(number); pos != std::string::npos) {
                const auto line = 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(pos), '\n');
                const auto bol = text.rfind('\n', pos);
                const auto column = 1 + pos - (bol == std::string::npos ? 0 : bol + 1);
                at = "line " + std::to_string(line) + ", column " + std::to_string(column) + ": ";
            }
            throw FileError(where + ": " + at + "the number " + printable(number, 40) + " is outside the range of a double (about 1.8e308)");
        }
        throw FileError(where + ": a number in the JSON is out of range (" + printable(msg, 300) + ")");
    }
}

json read_json_file(const std::string& path) { return parse_json(read_file(path), path); }

} // namespace drape
