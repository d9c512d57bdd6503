#pragma once
// The steps of measure_record, one file each (top_view.cpp, side_view.cpp,
// contour_levels.cpp). Internal to engine/capture.
#include "engine/capture/measure.hpp"

namespace drape::capture::detail {

/// Segments the top photo (out.top_image) and traces the outline into out.top.
void measure_top(const record::Record& rec, const MeasureOptions& opt, const record::ContourStack* stack, Measurement& out);
/// Sets the hem model's height error dz [m] and the totals that depend on it.
void set_hem_depth_error(TopView& tv, double dz);
/// Traces the hem in the side photo (out.side_image) into out.side; needs out.top.
void measure_side(const record::Record& rec, Measurement& out);
/// The pedestal's diameter from its silhouette in the side photo (out.side_image)
/// into out.side.pedestal; needs nothing of the top view.
void measure_pedestal(const record::Record& rec, Measurement& out);
/// Fourier series of every contour depth into out.contours.
void measure_contours(const record::Record& rec, const record::ContourStack& st, Measurement& out);

} // namespace drape::capture::detail
