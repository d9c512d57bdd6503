#include "cli/record_args.hpp"

#include "cli/command.hpp"
#include "engine/core/text.hpp"

#include <filesystem>
#include <map>

namespace drape::cli {

namespace fs = std::filesystem;

namespace {

/// Where `dir` is: its resolved path (symbolic links followed) when it can be
/// resolved, else its absolute, normal spelling; without a trailing separator.
fs::path location(const std::string& dir)
{
    std::error_code ec;
    // Absolute first: libstdc++'s weakly_canonical leaves a relative path whose
    // first part does not exist as it is ("none" but "/cwd/none" for "./none").
    fs::path p = fs::absolute(fs::path(dir), ec);
    if (ec) p = fs::path(dir);
    const fs::path resolved = fs::weakly_canonical(p, ec);
    p = (ec ? p : resolved).lexically_normal();
    if (!p.has_filename() && p.has_parent_path() && p != p.root_path()) p = p.parent_path();
    return p;
}

} // namespace

void reject_duplicate_records(const std::vector<std::string>& dirs)
{
    std::map<fs::path, std::string> seen; // location -> the first spelling
    for (const auto& d : dirs) {
        const fs::path where = location(d);
        const auto [it, fresh] = seen.emplace(where, d);
        if (fresh) continue;
        std::string msg = "RECORD_DIR: '";
        if (it->second == d) {
            msg.append(printable(d)).append("' is given twice");
        } else {
            msg.append(printable(it->second)).append("' and '").append(printable(d)).append("' are the same record folder (");
            msg.append(printable(where.string())).append(")");
        }
        msg.append("; each record counts once, give it once");
        throw UsageError(msg);
    }
}

} // namespace drape::cli
