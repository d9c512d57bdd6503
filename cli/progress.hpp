#pragma once
// Progress on stderr for the long commands (simulate, predict, fit, measure),
// one helper for all of them: on a terminal, one line rewritten in place with
// the percentage and the time left; when stderr is not a terminal (a log file,
// a pipe, CI), plain lines without carriage returns, at most one every few
// seconds, so a log reads like a log.
#include "engine/cloth/solver.hpp"

#include <chrono>
#include <string>

namespace drape::cli {

class Progress {
public:
    /// `label` starts every line ("simulate", "fit"). `quiet`: prints nothing.
    explicit Progress(std::string label, bool quiet = false);
    ~Progress(); ///< ends a terminal line that is still open

    /// fraction in [0, 1], or negative when unknown; `detail` is the rest of the
    /// line ("Newton iteration 12, residual 3e-04"). Cheap when nothing is printed.
    /// `now`: print it even within the interval since the last line (a new stage
    /// starting: a log would otherwise lose it to the throttle).
    void update(double fraction, const std::string& detail, bool now = false);
    /// The last line, with the total time: at 100 % when `complete`, else at the
    /// last fraction reached (a solve that stopped short).
    void finish(const std::string& detail = {}, bool complete = true);

    /// For RestOptions::progress: the residual's way from its first value down
    /// to `target` on a log scale as the fraction (never going back), or
    /// simulated time over `max_sim_time` for the dynamic integrators.
    std::function<bool(const cloth::SolverStatus&)> solver_callback(const cloth::RestOptions& ro);

    bool terminal() const { return m_tty; }

private:
    std::string line(double fraction, const std::string& detail) const;

    std::string m_label;
    bool m_quiet = false;
    bool m_tty = false;
    bool m_open = false; ///< a terminal line without its newline yet
    std::chrono::steady_clock::time_point m_start, m_last;
    double m_fraction = -1;
};

/// "1 min 05 s", "12 s", "2 h 03 min".
std::string format_duration(double seconds);

} // namespace drape::cli
