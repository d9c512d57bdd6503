#pragma once
// A fabric preset: what Drapekit knows about one fabric, typed. The physics
// (continuum SI parameters, and for the seed's presets their exact grid
// springs), the model options, and what a library or a CAD wants to show
// about it: composition, where it came from, how well it fitted its
// measurements, and the drape coefficient it makes on a stated set-up.
//
// Files: "drapekit-fabric" v1 JSON (parameter keys from cloth::param_table,
// units in the key names) or the seed paper's "seed-19" JSON
// (seed_format.hpp). Unknown fields are kept and written back. The drape
// coefficient is a percentage everywhere (D = 31.7 means 31.7 %); presets
// written before that rule ("drape_coefficient": {"value": 0.317}) are read
// as the same percentage.
#include "engine/cloth/drape.hpp"
#include "engine/cloth/model.hpp"
#include "engine/cloth/params.hpp"
#include "engine/fabric/seed_format.hpp"

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

namespace drape::fabric {

/// Where a preset came from ("provenance" in the file).
struct Provenance {
    std::string tool;                ///< "drape fit", "class preset", "seed-19", ... ("kind" in older files)
    std::string date;                ///< ISO 8601 date or time (UTC)
    int grid = 0;                    ///< nodes across the specimen of the simulations that made it (0 = unknown)
    std::vector<std::string> records;///< ids of the drape-test records it was fitted to
    /// How the records' lab laid its specimens ("laying_load", a fraction of
    /// gravity in (0, 1]: cloth::DrapeSetup::laying_load), as the fit assumed it
    /// for its drapes from flat; 0 = not stated (presets before 2026-11-30, the
    /// starters): laid at once. `drape simulate`, `predict` and the widget lay a
    /// preset this way by default (FabricPreset::laying).
    double laying_load = 0;
    /// How wavy the lab's specimens lie when laid ("perturbation_m", the largest
    /// lift [m] of the flat start's seeded waviness: cloth::DrapeSetup::perturbation,
    /// in [0, 0.05]) as the fit assumed it for its drapes from flat; nullopt = not
    /// stated (presets before 2026-12-01, the starters): the engine's default.
    std::optional<double> perturbation_m;
    nlohmann::json details = nlohmann::json::object(); ///< everything else, verbatim
};

/// How a fitted preset reproduced its records ("fit" in the file).
struct FitSummary {
    double chi2 = 0;                 ///< sum of squared whitened residuals
    int dof = 0;                     ///< degrees of freedom
    /// chi2 / dof: the fit quality a library lists (about 1 = within the
    /// measurement noise; larger = the model misses the record).
    std::optional<double> reduced_chi2;
    bool grid_bound = false;         ///< a fitted bending length is below the fit's mesh spacing
    double sample_diameter_m = 0;    ///< set-up of the first record [m] (0 = unknown)
    double disc_diameter_m = 0;      ///< [m]
    nlohmann::json details = nlohmann::json::object(); ///< parameters, intervals, records, ...: verbatim
};

/// The drape coefficient of the preset on a stated drapemeter set-up ("drape_coefficient").
struct DrapeReference {
    double percent = 0;              ///< D [%]
    std::string kind = "simulated";  ///< "simulated" | "measured"
    double sample_diameter_m = 0;    ///< [m]
    double disc_diameter_m = 0;      ///< [m]
    std::string method;              ///< how it was obtained
    std::string date;                ///< ISO 8601
    nlohmann::json details = nlohmann::json::object();
};

struct FabricPreset {
    std::string name = "unnamed";
    cloth::FabricParams params;          ///< continuum SI values (a seed preset: its continuum equivalents)
    std::optional<SeedParams> seed;      ///< the exact grid constants of a seed-19 preset
    cloth::ModelOptions model;
    std::string composition;             ///< e.g. "100 % cotton"
    std::string source;                  ///< free text: where the fabric data came from
    std::string notes;
    std::optional<Provenance> provenance;
    std::optional<FitSummary> fit;
    std::optional<DrapeReference> drape;
    nlohmann::json extra = nlohmann::json::object(); ///< unknown fields: kept, written back

    bool is_seed() const { return seed.has_value(); }
    /// What the engine drapes: the continuum parameters, with the exact grid
    /// springs of a seed preset (cloth::Material). The only place that tells
    /// the two kinds of preset apart for the engine.
    cloth::Material material() const;
    /// The preset with its physics replaced by continuum parameters (a seed
    /// preset becomes a continuum one; name and descriptions are kept).
    void set_params(const cloth::FabricParams& p);
    /// The file format it is written in: "drapekit-fabric" or "seed-19".
    std::string format() const { return is_seed() ? "seed-19" : "drapekit-fabric"; }
    /// cloth::DrapeSetup::laying_load of a drapemeter drape of this preset from
    /// flat: its records' lab's (Provenance::laying_load) when the fit stated
    /// it, else 1 (the whole load at once).
    double laying() const { return provenance && provenance->laying_load > 0 ? provenance->laying_load : 1.0; }
    /// cloth::DrapeSetup::perturbation of a drape of this preset from flat: its
    /// records' lab's (Provenance::perturbation_m) when the fit stated it, else
    /// the engine's default, cloth::kStartLift.
    double perturbation() const { return provenance && provenance->perturbation_m ? *provenance->perturbation_m : cloth::kStartLift; }
    /// `s` laid as this preset's lab laid its specimens (laying() and
    /// perturbation()): how `drape simulate`, predict, the widget and the
    /// benchmarks drape the preset from flat unless told otherwise.
    cloth::DrapeSetup laid(cloth::DrapeSetup s) const
    {
        s.laying_load = laying();
        s.perturbation = perturbation();
        return s;
    }
};

/// The built-in presets by name ("seed-table1": the seed paper's Table 1).
/// nullopt for other names.
std::optional<FabricPreset> builtin_fabric(const std::string& name);

/// Reads a preset file or a built-in name. Throws FileError / ParameterError
/// naming the file, field and value.
FabricPreset load_fabric(const std::string& path_or_name);
FabricPreset fabric_from_json(const nlohmann::json& j, const std::string& where);
nlohmann::json fabric_to_json(const FabricPreset& p);
/// Writes atomically (temporary file + rename) so a failed write never loses the old file.
void save_fabric(const FabricPreset& p, const std::string& path);

} // namespace drape::fabric
