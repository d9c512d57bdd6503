// The headless `drape` command: dispatches to the registered sub-commands.
#include "command.hpp"

#include "engine/cloth/error.hpp"
#include "engine/cloth/units.hpp"

#include <cstdio>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
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
                m_values[key] = value;
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
    return it->second;
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
    std::size_t pos = 0;
    double v = 0;
    try {
        v = std::stod(*s, &pos);
    } catch (const std::exception&) {
        pos = 0;
    }
    if (pos != s->size() || pos == 0) throw UsageError(flag + ": '" + *s + "' is not a number");
    return v;
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

namespace {
void print_overview()
{
    std::cout << "usage: drape COMMAND [ARGS]\n\ncommands:\n";
    for (const auto& [name, c] : drape::cli::registry())
        std::printf("  %-12s %s\n", name.c_str(), c.summary.c_str());
    std::cout << "\n`drape help COMMAND` shows a command's flags.\n";
}
} // namespace

int main(int argc, char** argv)
{
    using namespace drape::cli;
    std::vector<std::string> args(argv + 1, argv + argc);
    if (args.empty() || args[0] == "--help" || args[0] == "-h") {
        print_overview();
        return args.empty() ? 2 : 0;
    }
    if (args[0] == "help") {
        if (args.size() > 1) {
            auto it = registry().find(args[1]);
            if (it == registry().end()) {
                std::cerr << "drape: unknown command '" << args[1] << "'\n";
                return 2;
            }
            std::cout << it->second.usage << "\n";
            return 0;
        }
        print_overview();
        return 0;
    }
    auto it = registry().find(args[0]);
    if (it == registry().end()) {
        std::cerr << "drape: unknown command '" << args[0] << "' (see `drape --help`)\n";
        return 2;
    }
    std::vector<std::string> rest(args.begin() + 1, args.end());
    for (const auto& a : rest)
        if (a == "--help" || a == "-h") {
            std::cout << it->second.usage << "\n";
            return 0;
        }
    try {
        return it->second.run(rest);
    } catch (const UsageError& e) {
        std::cerr << "drape " << args[0] << ": " << e.what() << "\n\n" << it->second.usage << "\n";
        return 2;
    } catch (const drape::Error& e) {
        std::cerr << "drape " << args[0] << ": error: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "drape " << args[0] << ": internal error: " << e.what() << "\n";
        return 3;
    }
}
