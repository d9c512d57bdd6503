#pragma once
// Sensitivity study, as in the seed paper: one parameter varied at a time
// around a preset, the drape's appearance (D, nodes, harmonic magnitudes of the
// shadow outline, hem height) recorded for each value.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/params.hpp"

#include <atomic>
#include <functional>
#include <string>
#include <vector>

namespace drape::estimate {

struct SensitivityOptions {
    cloth::DrapeSetup setup;      ///< geometry, grid (default 25 here) and perturbation seed
    std::vector<cloth::Param> params = {cloth::Param::BendWarp, cloth::Param::BendWeft, cloth::Param::Shear,
                                        cloth::Param::StretchWarp, cloth::Param::StretchWeft, cloth::Param::AreaDensity};
    int steps = 5;                ///< values per parameter (odd: the preset's value is the middle one)
    double span_decades = 1.0;    ///< log parameters vary by 10^(+-span); linear ones by +-50 % of the range
    int harmonics = 8;
    int threads = 2;
    cloth::ModelOptions model;    ///< engine options of every drape (the preset's model)
    std::function<void(int done, int total)> progress;
    const std::atomic<bool>* cancel = nullptr;
    SensitivityOptions() { setup.grid = 25; }
};

struct SensitivityRow {
    cloth::Param param{};
    double value = 0;             ///< [parameter unit]
    double factor = 1;            ///< value / preset value (log parameters)
    double drape_coefficient_percent = 0;
    int node_count = 0;
    double hem_min_z = 0;         ///< [m]
    std::vector<double> harmonic_magnitudes_m; ///< shadow outline |c_k|, k = 1..harmonics
    bool converged = false;
};

/// Runs the study. Throws ParameterError on bad options.
std::vector<SensitivityRow> sensitivity_study(const cloth::FabricParams& base, const SensitivityOptions& opt);

/// Writes sensitivity.csv and one PNG per parameter (D and nodes, harmonic
/// magnitudes against the parameter). Returns the files written.
std::vector<std::string> write_sensitivity(const std::vector<SensitivityRow>& rows, const cloth::FabricParams& base,
                                           const std::string& dir);

} // namespace drape::estimate
