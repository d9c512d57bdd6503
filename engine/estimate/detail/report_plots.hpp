#pragma once
// The fit report's plots (report_plots.cpp), drawn by write_fit_report. Internal
// to the estimate layer.
#include "engine/estimate/fit_types.hpp"

#include <string>

namespace drape::estimate::detail {

/// printf-style formatting of one number.
std::string fmt(const char* f, double v);

/// Rotation [rad] that best lines the simulated folds up with the measured ones at
/// the deepest common depth (fold positions are random, so the plots compare
/// shapes after this rotation; the fit itself never uses phases).
double best_rotation(const RecordFit& rf);

/// A record's contours, measured and fitted (rotated by `rot`), seen from above.
void outline_plot(const RecordFit& rf, double rot, const std::string& path);
/// The record's top photo with the fitted outline over it; false without a photo.
bool top_overlay(const RecordFit& rf, double rot, const std::string& path);
/// r(theta) per depth, measured and fitted.
void r_theta_plot(const RecordFit& rf, double rot, const std::string& path);
/// The harmonic magnitudes per depth of record `record`, measured and fitted.
void harmonic_plot(const FitResult& fr, int record, const std::string& path);
/// The fitted parameters with their 95 % intervals.
void parameter_plot(const FitResult& fr, const std::string& path);
/// The candidate effects' z and delta chi2.
void candidates_plot(const FitResult& fr, const std::string& path);
/// chi2 over the evaluations.
void convergence_plot(const FitResult& fr, const std::string& path);

} // namespace drape::estimate::detail
