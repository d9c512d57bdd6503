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

bool Args::get_on_off(const std::string& flag, bool fallback) const
{
    const auto v = get(flag);
    if (!v) return fallback;
    if (*v != "on" && *v != "off") throw UsageError(flag + ": '" + *v + "' must be on or off");
    return *v == "on";
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

// ---- progress on stderr (progress.hpp) ------------------------------------------

#include "cli/progress.hpp"

#include <algorithm>
#include <cstdio>
#include <memory>
#include <sys/ioctl.h>

namespace drape::cli {

namespace {
/// Plain lines (not a terminal): at most one every this many seconds.
constexpr double kPlainInterval = 5.0;
/// A terminal line is redrawn at most this often.
constexpr double kTerminalInterval = 0.1;

/// A progress line cut to the terminal's width less one column (100 when the
/// width is not known), at a UTF-8 character boundary.
std::string fit_terminal(const std::string& s)
{
    winsize w{};
    const std::size_t cols = ::ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col > 10 ? w.ws_col : 101;
    if (s.size() < cols) return s;
    std::size_t n = cols - 1;
    while (n > 0 && (static_cast<unsigned char>(s[n]) & 0xC0) == 0x80) --n; // not inside a character
    return s.substr(0, n);
}
} // namespace

std::string format_duration(double s)
{
    char buf[48];
    if (!(s >= 0) || s > 1e7) return "?";
    if (s < 60) std::snprintf(buf, sizeof buf, "%.0f s", s);
    else if (s < 3600) std::snprintf(buf, sizeof buf, "%d min %02d s", int(s) / 60, int(s) % 60);
    else std::snprintf(buf, sizeof buf, "%d h %02d min", int(s) / 3600, (int(s) % 3600) / 60);
    return buf;
}

Progress::Progress(std::string label, bool quiet)
    : m_label(std::move(label)), m_quiet(quiet), m_tty(::isatty(STDERR_FILENO) == 1),
      m_start(std::chrono::steady_clock::now()), m_last(m_start - std::chrono::hours(1))
{
}

Progress::~Progress()
{
    if (m_open) std::fputc('\n', stderr);
}

std::string Progress::line(double fraction, const std::string& detail) const
{
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - m_start).count();
    std::string s = "  " + m_label;
    if (fraction >= 0) {
        char buf[64];
        std::snprintf(buf, sizeof buf, " %3.0f %%", 100 * fraction);
        s += buf;
        // The time left once there is something to extrapolate from.
        if (fraction >= 0.02 && fraction < 1) s += ", about " + format_duration(elapsed * (1 - fraction) / fraction) + " left";
    }
    s += " (" + format_duration(elapsed) + ")";
    if (!detail.empty()) s += "  " + detail;
    return s;
}

void Progress::update(double fraction, const std::string& detail, bool at_once)
{
    if (m_quiet) return;
    if (fraction >= 0) m_fraction = fraction;
    const auto now = std::chrono::steady_clock::now();
    const double since = std::chrono::duration<double>(now - m_last).count();
    if (!at_once && since < (m_tty ? kTerminalInterval : kPlainInterval)) return;
    m_last = now;
    const std::string s = line(m_fraction, detail);
    if (m_tty) {
        // Rewritten in place: cut to the terminal's width (a wrapped line cannot be
        // returned to with \r) and the rest of the old line cleared.
        std::fprintf(stderr, "\r%s\033[K", fit_terminal(s).c_str());
        m_open = true;
    } else {
        std::fprintf(stderr, "%s\n", s.c_str());
    }
    std::fflush(stderr);
}

void Progress::finish(const std::string& detail, bool complete)
{
    if (m_quiet) return;
    const std::string s = line(complete ? 1.0 : m_fraction, detail.empty() ? "done" : detail);
    if (m_tty) std::fprintf(stderr, "\r%s\033[K\n", fit_terminal(s).c_str());
    else std::fprintf(stderr, "%s\n", s.c_str());
    m_open = false;
    std::fflush(stderr);
}

std::function<bool(const cloth::SolverStatus&)> Progress::solver_callback(const cloth::RestOptions& ro)
{
    struct State {
        double r0 = -1, fraction = 0;
    };
    auto st = std::make_shared<State>();
    const bool statics = ro.integrator == cloth::Integrator::Static;
    const double target = ro.residual, max_time = ro.max_sim_time;
    return [this, st, statics, target, max_time](const cloth::SolverStatus& s) {
        double f = -1;
        if (statics) {
            if (st->r0 < 0 && s.residual > 0) st->r0 = s.residual;
            // A continuation solve starts again on each grid: the fraction never goes back.
            if (st->r0 > target && s.residual > 0)
                st->fraction = std::max(st->fraction, std::clamp(std::log(st->r0 / s.residual) / std::log(st->r0 / target), 0.0, 0.99));
            f = st->fraction;
        } else if (max_time > 0) {
            f = std::clamp(s.sim_time / max_time, 0.0, 0.99); // an upper bound: rest usually comes sooner
        }
        char buf[128];
        if (statics) std::snprintf(buf, sizeof buf, "iteration %ld, residual %.2e", s.newton_iterations, s.residual);
        else std::snprintf(buf, sizeof buf, "%ld steps, t = %.3f s, residual %.2e", s.steps, s.sim_time, s.residual);
        update(f, buf);
        return true;
    };
}

} // namespace drape::cli
