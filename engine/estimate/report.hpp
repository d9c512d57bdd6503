#pragma once
// The fit report folder: per record the measured and fitted contours (over the
// top photo when the record has a calibrated one, else a plot), r(theta) per
// depth measured vs fitted, the residual per harmonic; the parameter table with
// intervals; as PNG plots, report.json and a readable report.md.
#include "engine/estimate/fit.hpp"

#include <string>
#include <vector>

namespace drape::estimate {

/// Writes the report into `dir` (created). Returns the files written (paths
/// relative to `dir`). Throws FileError when a file cannot be written.
std::vector<std::string> write_fit_report(const FitResult& r, const std::string& dir, const std::string& preset_path = "");

/// Markdown table of the parameter estimates (used by the report and the CLI).
std::string parameter_table_markdown(const FitResult& r);

} // namespace drape::estimate
