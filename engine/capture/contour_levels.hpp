#pragma once
// The laser contours as Fourier series, one level per depth, with the number
// of harmonics the data supports.
#include "engine/cloth/metrics.hpp"

namespace drape::capture {

struct ContourLevel {
    double depth = 0;             ///< below the pedestal top [m]
    int points = 0;               ///< rays with data
    bool complete = false;        ///< all rays hit
    double mean_radius = 0;       ///< Fourier a0 [m]
    int harmonics = 0;            ///< chosen from the data (choose_harmonics)
    cloth::FourierSeries fit;     ///< r(theta) [m]
    double residual_rms = 0;      ///< [m]
    double noise_sigma = 0;       ///< declared repeatability [m]
    double max_jump = 0;          ///< largest |r_k+1 - r_k| between neighbouring rays [m] (overhangs)
};

} // namespace drape::capture
