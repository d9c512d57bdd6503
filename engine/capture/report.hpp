#pragma once
// What a measurement shows a person or a program: the JSON report and the
// overlay picture on the top photo.
#include "engine/capture/measure.hpp"

#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace drape::capture {

/// JSON report (SI units with the unit in each key name).
nlohmann::ordered_json to_json(const Measurement& m);

/// Overlay on the top photo: traced outline, nodes, pedestal circle, specimen circle.
cv::Mat draw_top_overlay(const record::Record& rec, const Measurement& m);

} // namespace drape::capture
