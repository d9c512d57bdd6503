#pragma once
// The fabric library: fitted and hand-made fabric presets in one SQLite file,
// managed like a garment CAD manages its materials.
//
// Durability: the database runs in WAL mode with synchronous=FULL and every
// write is one transaction (BEGIN IMMEDIATE ... COMMIT), so a crash, a kill or
// a full disk in the middle of a write leaves the library as it was before
// that write; a committed write survives a power cut. Readers (the CAD and the
// CLI at the same time) see a consistent snapshot while a writer works; writers
// queue behind each other with a busy timeout.
//
// Schema: PRAGMA user_version holds the schema version and application_id
// marks the file as a Drapekit library. Opening a read-write library with an
// older schema migrates it in one transaction; a newer schema is refused.
// The preset JSON (engine/cloth/fabric_io.hpp) is stored verbatim; the
// searchable columns (composition, weight, D, fit quality) are derived from it
// on every write.
#include "engine/fabric/preset.hpp"

#include <nlohmann/json.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

struct sqlite3;

namespace drape::library {

/// One stored fabric.
struct FabricRecord {
    std::int64_t id = 0;
    std::string name;                      ///< unique (case-insensitive)
    std::string composition;               ///< e.g. "100 % cotton"; from preset "composition"
    std::string format;                    ///< "drapekit-fabric" or "seed-19"
    double areal_density_kg_m2 = 0;        ///< weight [kg/m^2]
    std::optional<double> drape_coefficient_percent; ///< D [%] of the preset's drape reference
    std::optional<double> fit_quality;     ///< reduced chi-square of the preset's fit (about 1 = within noise)
    std::string created, modified;         ///< ISO 8601 UTC, e.g. "2026-11-22T01:02:03Z"
    int revision = 1;                      ///< 1 on add, +1 on every update or rename
    fabric::FabricPreset preset;
    nlohmann::json preset_json;            ///< the stored preset file contents
};

enum class SortKey { Name, Weight, DrapeCoefficient, Modified, FitQuality };

/// Search and filter. Empty / unset fields do not filter. Text matches are
/// case-insensitive substrings. Records without D or fit quality drop out of
/// a filter on that field.
struct Filter {
    std::string text;                  ///< in name, composition or the preset's "source"/"notes"
    std::string name;                  ///< substring of the name
    std::string composition;           ///< substring of the composition
    std::optional<double> weight_min, weight_max;   ///< [kg/m^2]
    std::optional<double> drape_min, drape_max;     ///< D [%]
    std::optional<double> fit_min, fit_max;         ///< fit quality
    std::string modified_from, modified_to;         ///< ISO 8601 dates or times, inclusive ("2026-11-01")
    SortKey sort = SortKey::Name;
    bool descending = false;
    int limit = 0;                     ///< 0 = all
};

/// What to do when an imported fabric's name already exists.
enum class OnConflict { Fail, Skip, Replace, Rename };

struct ImportReport {
    int added = 0, replaced = 0, skipped = 0, renamed = 0;
    std::vector<std::string> names; ///< stored names, in input order
};

enum class PresetFormat { Drapekit, Seed19 };

class FabricLibrary {
public:
    enum class Mode { ReadWrite, ReadOnly };
    /// 3: D in percent, fit quality = reduced chi-square, presets in the typed format.
    static constexpr int kSchemaVersion = 3;
    static constexpr std::int32_t kApplicationId = 0x44524150; ///< "DRAP"

    /// Opens (ReadWrite: creates, with its parent folder, or migrates) the
    /// library at `path`. Throws FileError naming the path when the file is not
    /// a SQLite database, is another application's database, has a newer
    /// schema, is missing in ReadOnly mode, or cannot be opened.
    explicit FabricLibrary(const std::string& path, Mode mode = Mode::ReadWrite);
    ~FabricLibrary();
    FabricLibrary(FabricLibrary&&) noexcept;
    FabricLibrary& operator=(FabricLibrary&&) noexcept;
    FabricLibrary(const FabricLibrary&) = delete;
    FabricLibrary& operator=(const FabricLibrary&) = delete;

    const std::string& path() const { return m_path; }
    int schema_version() const;

    /// Adds a preset under `name` (empty: the preset's own name). Throws
    /// ParameterError when the name is taken or invalid. Returns the id.
    std::int64_t add(const fabric::FabricPreset& preset, const std::string& name = {});
    /// Replaces the preset stored under `name` (its name stays `name`).
    void update(const std::string& name, const fabric::FabricPreset& preset);
    void rename(const std::string& from, const std::string& to);
    void remove(const std::string& name);
    /// Removes every named fabric in one transaction: when one name is not in
    /// the library, nothing is removed (ParameterError naming it).
    void remove(const std::vector<std::string>& names);

    std::optional<FabricRecord> find(const std::string& name) const;
    FabricRecord get(const std::string& name) const; ///< throws ParameterError when absent
    std::vector<FabricRecord> list(const Filter& filter = {}) const;
    int count() const;

    /// A preset file's JSON ("drapekit-fabric" or, for seed presets, "seed-19").
    nlohmann::json export_preset(const std::string& name, PresetFormat format = PresetFormat::Drapekit) const;
    /// Parses a preset JSON in either format (`where` names its origin in errors) and adds it.
    std::int64_t import_preset(const nlohmann::json& j, const std::string& where, const std::string& name = {},
                               OnConflict on_conflict = OnConflict::Fail);

    /// The whole library as one JSON document {"format": "drapekit-fabric-library",
    /// "version": 1, "fabrics": [...]}, read in one snapshot.
    nlohmann::json export_all() const;
    /// Imports a whole-library document (or a JSON array of presets) in one
    /// transaction: either every fabric goes in or none does.
    ImportReport import_all(const nlohmann::json& doc, const std::string& where, OnConflict on_conflict = OnConflict::Fail);

    /// Tests only: caps the database size at `pages` pages for this connection,
    /// so a write fails with SQLITE_FULL the way a full disk makes it fail.
    void limit_pages_for_testing(std::int64_t pages);

private:
    void migrate();
    /// The name a fabric called `name` is stored under (its normalised form
    /// when that is in the library, else `name` as given).
    std::string stored_name(const std::string& name) const;
    /// `created`: the date a new row keeps (a bulk import's, from the
    /// exporting library); empty = now.
    std::int64_t put(const fabric::FabricPreset& preset, const std::string& name, OnConflict on_conflict,
                     ImportReport* report, const std::string& created = {});

    sqlite3* m_db = nullptr;
    std::string m_path;
    Mode m_mode = Mode::ReadWrite;
};

/// The default library path: $DRAPE_LIBRARY, else
/// $XDG_DATA_HOME/drapekit/library.sqlite, else ~/.local/share/drapekit/library.sqlite.
std::string default_library_path();

/// Longest fabric name [characters (Unicode code points), not bytes].
inline constexpr std::size_t kMaxNameChars = 200;

/// The name as the library stores and looks it up: Unicode NFC, leading and
/// trailing white space removed (no-break spaces too), 1..kMaxNameChars
/// characters, no control characters (drape::normalize_name). So "silk" with a
/// trailing no-break space, or "Café" typed with a combining accent, is the
/// fabric already called "silk" or "Café". Throws ParameterError naming the
/// name and what is wrong with it.
std::string normalize_name(const std::string& name);
/// Throws the same ParameterError, or returns quietly for a valid name.
void validate_name(const std::string& name);
/// True for an ISO 8601 date or date-time prefix ("2026", "2026-11-22", "2026-11-22T10:30"),
/// the form Filter::modified_from/to take.
bool is_iso_date(const std::string& text);

} // namespace drape::library
