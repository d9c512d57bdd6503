#pragma once
// Synthetic drape-test records for the estimator's tests: a drape simulated
// with known parameters, measured as the lab would (0.3 mm laser noise).
#include "engine/estimate/measured.hpp"

#include <cstdint>
#include <string>

namespace drape::estimate::test {

inline cloth::DrapeSetup drape_setup(double D1, double D2, int grid, std::uint64_t seed)
{
    cloth::DrapeSetup s;
    s.sample_diameter = D1;
    s.disc_diameter = D2;
    s.grid = grid;
    s.seed = seed;
    return s;
}

/// Simulates `p` on `s` and turns the rest state into a record (noise seeded by s.seed + 100).
inline MeasuredDrape synthetic_record(const cloth::FabricParams& p, const cloth::DrapeSetup& s, const std::string& id = "synthetic")
{
    return synthesize_record(cloth::simulate_drape(p, s), s, p, 0.3e-3, s.seed + 100, id);
}

} // namespace drape::estimate::test
