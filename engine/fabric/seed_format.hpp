#pragma once
// The seed paper's 19 synthetic parameters (Kuzmina, Tamas, Halasz, Grof,
// "Image-based cloth capture and cloth simulation used for estimation cloth
// draping parameters", Table 1). They are grid constants, not continuum
// values: they describe one particular 30 x 30 grid. Drapekit reads and writes
// them exactly (the "seed-19" preset format), and simulates them on the grid
// they describe (cloth::GridSprings).
//
// Units: the paper states none. Drapekit reads them as
//   w, h, x0, y0, z0 in centimetres (w = 30 is the paper's 30 cm specimen and
//   the table radius 7.5 its 15 cm disc), so a patch is 1 cm^2;
//   ClothOverMass in 1/(0.01 g): a particle of 1/ClothOverMass = 2 units then
//   weighs 0.02 g on its 1 cm^2, i.e. 200 g/m^2, the middle of apparel fabrics
//   (the lab batch spans 80-450 g/m^2). The literal gram reading would make
//   the sheet 20 kg/m^2, a rubber mat (it drapes to D = 12.8 % with 12 nodes);
//   spring constants in N/m, dampers in N*s/m.
// This is an interpretation, declared here once (kSeedMassUnitKg) and used by
// both directions, so import and export stay exact whatever one thinks of it.
#include "engine/cloth/model.hpp"
#include "engine/cloth/params.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace drape::fabric {

/// Mass unit of ClothOverMass [kg] (see above).
inline constexpr double kSeedMassUnitKg = 1e-5;
/// Ranges of the seed fields (validate()): sheet size and corner [cm], cells
/// along u and v (the engine drapes a seed preset on its own grid, so at most
/// what --grid allows), springs [N/m] (the table's stretch bound) and dampers
/// [N*s/m] (the table's damper bound).
inline constexpr double kMaxSeedSizeCm = 1000;
inline constexpr int kMaxSeedCells = 1000;
inline constexpr double kMaxSeedSpring = 1e6;
inline constexpr double kMaxSeedDamper = 1e3;

struct SeedParams {
    double w = 30, h = 30;                  ///< size of cloth [cm]
    int u = 30, v = 30;                     ///< grid size: square patches along u and v (u + 1 nodes)
    double x0 = -15.0, y0 = 15.0, z0 = 0.0; ///< position of the cloth's corner [cm]
    double cloth_over_mass = 0.5;           ///< 1/mass of a particle [1/(0.01 g)]
    double sst_ku = 150, sst_du = 7, sst_kv = 150, sst_dv = 7; ///< structural springs [N/m], [N*s/m]
    double ssh_k = 40, ssh_d = 6;           ///< shear springs
    double sfl_ku = 24, sfl_du = 8, sfl_kv = 24, sfl_dv = 8;   ///< flexion (skip-one) springs

    /// The paper's Table 1 ("Parameter values for the start run of simulator").
    static SeedParams table1() { return {}; }

    /// Grid spacing in metres along u and v (w/u, h/v in cm -> m).
    double hu_m() const;
    double hv_m() const;
    double particle_mass_kg() const;
    /// ParameterError naming the seed field (w, ClothOverMass, ...) and value.
    void validate(const std::string& where) const;
};

/// The seed's constants as the engine's grid springs (SI; exact).
cloth::GridSprings grid_springs(const SeedParams& s);

/// Equivalent continuum values of the seed constants on their own grid, by the
/// inverse of cloth::make_model's mapping (stretch, shear, mass, dampers). The
/// flexion springs have no continuum counterpart (they resist bending only at
/// second order, with a grid-dependent strength), so bending is left at its default.
cloth::FabricParams continuum_from_seed(const SeedParams& s);

/// The "seed-19" JSON object (format + the 19 keys) and back. `where` names
/// the document in errors (FileError / ParameterError naming the key).
nlohmann::json seed_to_json(const SeedParams& s);
SeedParams seed_from_json(const nlohmann::json& j, const std::string& where);
/// The 19 keys of the format (and "format"): what a seed-19 file holds besides free extras.
bool is_seed_key(const std::string& key);

} // namespace drape::fabric
