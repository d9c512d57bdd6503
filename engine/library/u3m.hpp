#pragma once
// Fabric presets as U3M, the Unified 3D Material format garment tools exchange
// materials in (Vizoo and Browzwear; U3M 1.1, the JSON schema
// u3m1.1/spec/u3m_schema.json of github.com/vizoogmbh/u3m).
//
// What goes where:
//   * "material.physics" (the format's own fields): "weight" in g/m^2 and
//     "thickness" in mm, "composition" parts when the preset's composition text
//     reads as "NN % fibre, ..." with known fibres; construction and material
//     type are not known to Drapekit (null).
//   * "custom.drapekit" (the vendor block the format leaves to each tool): our
//     continuum parameters per direction, each with its unit and meaning
//     ({"stretch_warp_N_m": {"value": 2000, "unit": "N/m", "doc": "..."}, ...}:
//     stretch warp/weft [N/m], shear [N/m], bending warp/weft [N*m], areal
//     density [kg/m^2], thickness [m], friction, damping), and the whole
//     preset as Drapekit writes it ("preset": drapekit-fabric or seed-19 JSON),
//     so a round trip through a U3M file keeps every field of ours.
//   * No visuals (front/back/side are null): a drape preset has no texture.
//
// Reading: the "preset" block when there is one, with the U3M's own weight and
// thickness taking precedence where another tool changed them (the format's
// rule for duplicated values); else the documented parameters; else (a U3M
// from another tool) the parameter table's defaults with the file's weight and
// thickness, named after the material.
#include "engine/fabric/preset.hpp"

#include <nlohmann/json.hpp>

#include <string>

namespace drape::library {

struct U3mOptions {
    std::string created;  ///< ISO 8601 UTC; empty = now
    std::string modified; ///< ISO 8601 UTC; empty = created
};

/// The preset as a U3M 1.1 document (material.id: a UUID4 derived from the name,
/// so exporting the same fabric twice gives the same id).
nlohmann::json preset_to_u3m(const fabric::FabricPreset& preset, const U3mOptions& opt = {});

/// True when `j` looks like a U3M document ({"schema": "1.x", "material": {...}}).
bool is_u3m(const nlohmann::json& j);

/// The preset a U3M document describes. `where` names the file in errors.
/// Throws ParameterError naming the field when the document is not U3M 1.0/1.1,
/// has no material name, or holds values outside the parameter table's bounds.
/// `note` (optional) receives what was taken from where, for the user.
fabric::FabricPreset preset_from_u3m(const nlohmann::json& j, const std::string& where, std::string* note = nullptr);

/// The composition text as U3M composition parts, e.g. "60 % cotton, 40 %
/// polyester" -> [{ratio 0.6, type "Cotton"}, {ratio 0.4, type "Polyester"}];
/// null when it does not read as fibres adding up to 100 %.
nlohmann::json composition_parts(const std::string& composition);

} // namespace drape::library
