// Command-line parsing shared by every sub-command (command.hpp).
#include "cli/command.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <unistd.h>

namespace drape::cli {

namespace {
/// `given` is what the user typed after `flag` (the file, or the folder itself).
void check_output_dir(const std::string& dir, const std::string& flag, const std::string& given)
{
    namespace fs = std::filesystem;
    const fs::path d = dir.empty() ? fs::path(".") : fs::path(dir);
    std::error_code ec;
    if (!fs::exists(d, ec)) {
        fs::create_directories(d, ec);
        if (ec) throw FileError(flag + " " + given + ": cannot create the folder " + d.string() + " (" + ec.message() + ")");
    }
    if (!fs::is_directory(d, ec)) throw FileError(flag + " " + given + ": " + d.string() + " is not a folder");
    const fs::path probe = d / (".drape-write-test-" + std::to_string(::getpid()));
    {
        std::ofstream f(probe);
        if (!f) throw FileError(flag + " " + given + ": cannot write in the folder " + d.string());
    }
    fs::remove(probe, ec);
}
} // namespace

void prepare_output_dir(const std::string& dir, const std::string& flag) { check_output_dir(dir, flag, dir); }

void prepare_output_file(const std::string& path, const std::string& flag)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    if (fs::is_directory(fs::path(path), ec)) throw FileError(flag + " " + path + ": is a folder, not a file");
    const fs::path parent = fs::path(path).parent_path();
    check_output_dir(parent.empty() ? std::string(".") : parent.string(), flag, path);
}

std::map<std::string, Command>& registry()
{
    static std::map<std::string, Command> r;
    return r;
}

Args::Args(const std::vector<std::string>& argv, const std::set<std::string>& value_flags,
           const std::set<std::string>& switches)
{
    for (std::size_t i = 0; i < argv.size(); ++i) {
        const std::string& a = argv[i];
        if (a.rfind("--", 0) == 0 && a.size() > 2) {
            std::string key = a, value;
            bool inline_value = false;
            if (auto eq = a.find('='); eq != std::string::npos) {
                key = a.substr(0, eq);
                value = a.substr(eq + 1);
                inline_value = true;
            }
            if (switches.count(key)) {
                if (inline_value) throw UsageError("flag " + key + " takes no value");
                m_switches.insert(key);
            } else if (value_flags.count(key)) {
                if (!inline_value) {
                    if (i + 1 >= argv.size()) throw UsageError("flag " + key + " needs a value");
                    value = argv[++i];
                }
                m_values[key].push_back(value);
            } else {
                throw UsageError("unknown flag '" + key + "'");
            }
        } else {
            m_pos.push_back(a);
        }
    }
}

bool Args::has(const std::string& flag) const { return m_switches.count(flag) || m_values.count(flag); }

std::optional<std::string> Args::get(const std::string& flag) const
{
    auto it = m_values.find(flag);
    if (it == m_values.end()) return std::nullopt;
    return it->second.back();
}

std::vector<std::string> Args::get_all(const std::string& flag) const
{
    auto it = m_values.find(flag);
    return it == m_values.end() ? std::vector<std::string>{} : it->second;
}

std::string Args::get_or(const std::string& flag, const std::string& fallback) const
{
    return get(flag).value_or(fallback);
}

int Args::get_int(const std::string& flag, int fallback, int min, int max) const
{
    auto s = get(flag);
    if (!s) return fallback;
    std::size_t pos = 0;
    long v = 0;
    try {
        v = std::stol(*s, &pos);
    } catch (const std::exception&) {
        pos = 0;
    }
    if (pos != s->size() || pos == 0) throw UsageError(flag + ": '" + *s + "' is not an integer");
    if (v < min || v > max)
        throw UsageError(flag + ": " + *s + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]");
    return static_cast<int>(v);
}

double Args::get_double(const std::string& flag, double fallback) const
{
    auto s = get(flag);
    if (!s) return fallback;
    // The one strict parser (units.hpp): a whole decimal number, finite ("inf",
    // "nan", "1e400", "0x1p-3" and "81.5abc" are refused).
    double v = 0;
    if (!parse_number(*s, v)) throw UsageError(flag + ": '" + *s + "' is not a finite number");
    return v;
}

double Args::get_double_in(const std::string& flag, double fallback, double lo, double hi, const std::string& unit) const
{
    const double v = get_double(flag, fallback);
    if (has(flag) && (v < lo || v > hi)) {
        const std::string u = unit.empty() ? "" : " " + unit;
        throw UsageError(flag + ": " + *get(flag) + u + " is outside [" + format_value(lo) + ", " + format_value(hi) + "]" + u);
    }
    return v;
}

std::string dump_json(const nlohmann::json& j, int indent)
{
    // Text from the command line or from file names need not be UTF-8; it is
    // written with U+FFFD instead of failing the whole output.
    return j.dump(indent, ' ', false, nlohmann::json::error_handler_t::replace);
}

double Args::get_length(const std::string& flag, double fallback) const
{
    auto s = get(flag);
    if (!s) return fallback;
    try {
        return parse_length(*s, flag);
    } catch (const Error& e) {
        throw UsageError(e.what());
    }
}

} // namespace drape::cli
