#pragma once
// Sub-command registry of the `drape` tool. Each cli/cmd_*.cpp registers one
// command with a static DRAPE_COMMAND(...) object; cli/CMakeLists.txt compiles
// every cmd_*.cpp straight into the executable, so the registrations are kept.
// A command's own names (kUsage, run, helpers) live in a namespace named after
// its file (cmd_fit): a unity build puts several commands in one unit.
#include <nlohmann/json_fwd.hpp>

#include <functional>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace drape::cli {

/// Parsed command line of one sub-command: --flag value pairs, bare --switches
/// and positionals. Unknown flags are an error (UsageError).
class Args {
public:
    /// `value_flags` take a value ("--out DIR" or "--out=DIR"), `switches` do not.
    Args(const std::vector<std::string>& argv, const std::set<std::string>& value_flags,
         const std::set<std::string>& switches);
    bool has(const std::string& flag) const;
    std::optional<std::string> get(const std::string& flag) const; ///< the last value given
    std::vector<std::string> get_all(const std::string& flag) const; ///< every value of a repeatable flag, in order
    std::string get_or(const std::string& flag, const std::string& fallback) const;
    /// "on" or "off" (UsageError naming the flag and value otherwise), `fallback` when absent.
    bool get_on_off(const std::string& flag, bool fallback) const;
    /// Integer / double values with a clear error naming the flag and value.
    int get_int(const std::string& flag, int fallback, int min, int max) const;
    double get_double(const std::string& flag, double fallback) const;
    /// A finite number in [lo, hi] (`unit` for the message), UsageError naming the flag otherwise.
    double get_double_in(const std::string& flag, double fallback, double lo, double hi, const std::string& unit = "") const;
    /// Length with unit suffix (mm, cm, m; bare = m) in metres.
    double get_length(const std::string& flag, double fallback) const;
    const std::vector<std::string>& positionals() const { return m_pos; }

private:
    std::map<std::string, std::vector<std::string>> m_values;
    std::set<std::string> m_switches;
    std::vector<std::string> m_pos;
};

/// JSON text for stdout and output files: bytes that are not UTF-8 (from a
/// command line or a file name) become U+FFFD instead of an exception.
std::string dump_json(const nlohmann::json& j, int indent = 2);

/// Thrown for a bad command line; main prints it with the usage and exits 2.
struct UsageError : std::runtime_error {
    using std::runtime_error::runtime_error;
};

/// Before a long job: creates the parent folder of the output file `path` (given
/// with `flag`) and checks that a file can be written there, so a fit does not
/// run for minutes and then fail to save. Throws drape::FileError naming both.
void prepare_output_file(const std::string& path, const std::string& flag);
/// The same for an output folder (created if missing).
void prepare_output_dir(const std::string& dir, const std::string& flag);

struct Command {
    std::string name;
    std::string summary;
    std::string usage;  ///< full usage text printed by `drape help NAME`
    std::function<int(const std::vector<std::string>&)> run; ///< returns the exit code
};

std::map<std::string, Command>& registry();

struct Registrar {
    explicit Registrar(Command c) { registry().emplace(c.name, std::move(c)); }
};

} // namespace drape::cli

#define DRAPE_CLI_CONCAT2(a, b) a##b
#define DRAPE_CLI_CONCAT(a, b) DRAPE_CLI_CONCAT2(a, b)
/// Usage: DRAPE_COMMAND({"name", "summary", usage_text, run_function});
#define DRAPE_COMMAND(...) static ::drape::cli::Registrar DRAPE_CLI_CONCAT(drape_cmd_, __COUNTER__)(__VA_ARGS__)
