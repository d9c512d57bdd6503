#pragma once
// Export of a continuum preset to the seed paper's 19 grid constants for a
// given grid ("export to the seed's 19-parameter format for a given
// grid").
//
// Mass, structural (stretch), shear springs and dampers follow exactly from the
// continuum values by the inverse of continuum_from_seed (seed_format.hpp). The
// flexion springs have no continuum counterpart: a skip-one spring resists a
// bend only at second order of the angle, with a strength that depends on the
// grid. They are therefore calibrated: one common flexion constant (warp : weft
// in the ratio of the preset's bending rigidities) is searched so that the seed
// model drapes to the same drape coefficient as the preset, on the same set-up
// and grid, averaged over the same perturbation seeds. The seed model's D does
// not reach every value: it saturates near 75 % for a 200 g/m^2 fabric at 300/150
// mm (flexion constants above ~300 N/m stiffen nothing more), and below it is
// floored by the mesh's membrane stiffness; outside, the nearest end is
// exported and the result says it did not match.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/params.hpp"
#include "engine/fabric/seed_format.hpp"

#include <functional>
#include <string>

namespace drape::estimate {

struct SeedExport {
    fabric::SeedParams seed;
    double target_dc_percent = 0;   ///< the preset's D on the set-up (seed-averaged)
    double seed_dc_percent = 0;     ///< the exported seed constants' D
    bool matched = false;           ///< |seed D - target D| <= tolerance
    int simulations = 0;
    std::string note;
};

/// Grid constants of `p` on a square seed grid of setup.grid - 1 patches across
/// setup.sample_diameter, flexion calibrated on D (see above). `seeds`
/// perturbation seeds per D; tolerance in points of D. Throws ParameterError when
/// the grid cannot carry the preset (stretch below shear: negative structural springs).
SeedExport export_seed(const cloth::FabricParams& p, const cloth::DrapeSetup& setup, const cloth::ModelOptions& model = {}, int seeds = 2,
                       double tolerance_percent = 0.5, const std::function<void(const std::string&)>& progress = {});

/// The exact part only: mass, structural and shear springs, dampers; flexion
/// constants 0. Exposed for tests (continuum_from_seed inverts it).
fabric::SeedParams seed_without_flexion(const cloth::FabricParams& p, double sample_diameter_m, int patches);

} // namespace drape::estimate
