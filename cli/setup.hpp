#pragma once
// What several commands read the same way: the drapemeter set-up flags and
// the fabric (a preset file or a built-in, with --set KEY=VALUE overrides from
// the parameter table). One parser, so a flag means the same in every command.
#include "cli/command.hpp"
#include "cli/record_args.hpp" // the RECORD_DIR arguments, read the same way by fit and compare

#include "engine/cloth/drape.hpp"
#include "engine/fabric/preset.hpp"

#include <optional>
#include <set>
#include <string>

namespace drape::cli {

/// The set-up flags a command takes (each a bit).
enum SetupFlag : unsigned {
    kSampleDiameter = 1u << 0, ///< --sample-diameter L
    kDiscDiameter = 1u << 1,   ///< --disc-diameter L
    kPedestalHeight = 1u << 2, ///< --pedestal-height L
    kEdgeRadius = 1u << 3,     ///< --edge-radius L
    kGrid = 1u << 4,           ///< --grid N
    kSeed = 1u << 5,           ///< --seed K
    kFolds = 1u << 6,          ///< --folds N, --fold-angle DEG
    kPerturbation = 1u << 7,   ///< --perturbation L
    kDiscGrip = 1u << 8,       ///< --disc-grip (a switch)
    kLaying = 1u << 9,         ///< --laying F (fraction of gravity of the first rest; DrapeSetup::laying_load)
    kMesh = 1u << 10,          ///< --mesh grid|rings (DrapeSetup::mesh)
    kAllSetup = (1u << 11) - 1,
};

/// `--laying F` (a fraction of gravity in [0.001, 1]; UsageError naming the
/// flag otherwise), or `fallback` when absent: parse_setup, fit and compare.
double parse_laying(const Args& a, double fallback);
/// `--perturbation L` (a length in [0, 50mm]; UsageError naming the flag and
/// value otherwise), `fallback` when absent.
double parse_perturbation(const Args& a, double fallback);

/// `--mesh grid|rings` (UsageError naming the flag and value otherwise), or
/// `fallback` when absent.
cloth::DrapeMesh parse_mesh(const Args& a, cloth::DrapeMesh fallback);

/// The mesh a fitted preset is draped on: `--mesh` when given, else the fit's
/// (provenance.mesh, "grid" or "rings"; a preset without it: the grid).
/// ParameterError naming the preset and field on a bad value.
cloth::DrapeMesh preset_mesh(const Args& a, const fabric::FabricPreset& preset);

/// The grid a fitted preset was fitted at, scaled to a specimen of `sample_diameter`
/// [m] (provenance.grid at the fit's first record's diameter, fit.sample_diameter_m,
/// else 300 mm): the same mesh density. None when the preset has no fit grid.
std::optional<int> preset_fit_grid(const fabric::FabricPreset& preset, double sample_diameter);

/// The value flags and switches of `which`, to merge into a command's Args.
std::set<std::string> setup_value_flags(unsigned which);
std::set<std::string> setup_switches(unsigned which);
/// Union of two flag sets (for building a command's Args).
std::set<std::string> operator+(std::set<std::string> a, const std::set<std::string>& b);

/// The set-up from `defaults` with the flags present in `a` applied (lengths
/// with units; --folds starts on the n-fold branch with the default lift,
/// --perturbation then sets the lift; --folds without --laying lays the sheet at
/// once, laying_load 1, so the prescribed branch is what it starts on). Bad values are UsageErrors naming the
/// flag; the result is validated (ParameterError on an impossible set-up).
cloth::DrapeSetup parse_setup(const Args& a, cloth::DrapeSetup defaults);

/// `--fabric F` (required) and every `--set KEY=VALUE`: a preset file, a
/// built-in, a fabric of the default library or a starter fabric by short name
/// (library::resolve_fabric), with parameters overridden from the parameter table (KEY a
/// table key, VALUE a number in the key's unit; e.g. --set bend_warp_Nm=2e-6).
/// An override turns a seed-19 preset into its continuum equivalent, and says
/// so on stderr (to_continuum). `fallback` (when not empty) is the fabric when
/// --fabric is not given.
fabric::FabricPreset load_fabric_flags(const Args& a, const std::string& fallback = {});
/// `preset` with its physics replaced by the continuum parameters `p`
/// (FabricPreset::set_params). A seed-19 preset becomes a continuum one, which
/// is a different model (its flexion springs have no continuum counterpart, and
/// it drapes on the command's grid, not its own): a note on stderr says so,
/// naming `flag` (what asked for the change) and the preset.
void to_continuum(fabric::FabricPreset& preset, const cloth::FabricParams& p, const std::string& flag);
/// The set-up `s` on the grid `preset` drapes on. A seed-19 preset's 19
/// constants are the springs of its own grid (u + 1 nodes across), where the
/// engine drapes it whatever the set-up says: `s.grid` becomes that grid (so
/// a summary reports the mesh that was draped), and a `--grid` naming another
/// is a UsageError. A continuum preset's `s` is returned as it is.
cloth::DrapeSetup on_preset_grid(const Args& a, const fabric::FabricPreset& preset, cloth::DrapeSetup s);
/// "seed-19" (the preset's own grid springs) or "continuum": what a summary
/// reports as "fabric_model".
const char* fabric_model_name(const fabric::FabricPreset& preset);
/// The value flags load_fabric_flags reads: --fabric and --set.
std::set<std::string> fabric_flags();
/// p with every --set KEY=VALUE applied (a key of the parameter table, a value
/// inside its bounds; UsageError naming the flag, key and value otherwise).
cloth::FabricParams apply_set_flags(const Args& a, cloth::FabricParams p);
/// The items of a comma-separated list, in order (empty items kept: "a,,b" has three).
std::vector<std::string> split_list(const std::string& list);

} // namespace drape::cli
