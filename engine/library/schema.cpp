#include "engine/library/schema.hpp"

#include "engine/core/io.hpp"
#include "engine/library/sqlite.hpp"

#include <functional>
#include <utility>
#include <vector>

namespace drape::library {

using nlohmann::json;
using sql::exec;
using sql::Stmt;

Columns derive_columns(const fabric::FabricPreset& p)
{
    Columns c;
    c.format = p.format();
    c.composition = p.composition;
    c.weight = p.params[cloth::Param::AreaDensity];
    if (p.drape) c.drape_percent = p.drape->percent;
    if (p.fit) c.fit_quality = p.fit->reduced_chi2;
    return c;
}

namespace {

/// Re-reads every stored preset (with the preset reader's legacy rules),
/// writes it back in the current format and derives its columns again.
void rewrite_presets(sqlite3* db, const std::string& path)
{
    std::vector<std::pair<std::int64_t, fabric::FabricPreset>> rows;
    {
        Stmt s(db, path, "SELECT id, name, preset FROM fabrics");
        while (s.step()) {
            const std::string where = path + ": fabric '" + s.text(1) + "'";
            rows.emplace_back(s.integer(0), fabric::fabric_from_json(parse_json(s.text(2), where), where));
        }
    }
    for (const auto& [id, p] : rows) {
        const Columns c = derive_columns(p);
        Stmt u(db, path,
               "UPDATE fabrics SET preset = ?1, format = ?2, composition = ?3, areal_density = ?4, drape_coefficient = ?5,"
               " fit_quality = ?6 WHERE id = ?7");
        u.bind(1, fabric::fabric_to_json(p).dump()).bind(2, c.format).bind(3, c.composition).bind(4, c.weight);
        u.bind(5, c.drape_percent).bind(6, c.fit_quality).bind(7, id);
        u.run();
    }
}

using Migration = std::function<void(sqlite3*, const std::string&)>;

const std::vector<Migration>& migrations()
{
    static const std::vector<Migration> m = {
        // 0 -> 1: the first schema, presets stored verbatim.
        [](sqlite3* db, const std::string& path) {
            exec(db, path,
                 "CREATE TABLE fabrics ("
                 " id INTEGER PRIMARY KEY,"
                 " name TEXT NOT NULL UNIQUE COLLATE NOCASE,"
                 " preset TEXT NOT NULL,"
                 " created TEXT NOT NULL,"
                 " modified TEXT NOT NULL)");
        },
        // 1 -> 2: searchable columns derived from the preset (filled in by 2 -> 3).
        [](sqlite3* db, const std::string& path) {
            exec(db, path,
                 "ALTER TABLE fabrics ADD COLUMN format TEXT NOT NULL DEFAULT 'drapekit-fabric';"
                 "ALTER TABLE fabrics ADD COLUMN composition TEXT NOT NULL DEFAULT '';"
                 "ALTER TABLE fabrics ADD COLUMN areal_density REAL NOT NULL DEFAULT 0;"
                 "ALTER TABLE fabrics ADD COLUMN drape_coefficient REAL;"
                 "ALTER TABLE fabrics ADD COLUMN fit_quality REAL;"
                 "ALTER TABLE fabrics ADD COLUMN revision INTEGER NOT NULL DEFAULT 1;"
                 "CREATE INDEX fabrics_weight ON fabrics(areal_density);"
                 "CREATE INDEX fabrics_drape ON fabrics(drape_coefficient);"
                 "CREATE INDEX fabrics_modified ON fabrics(modified);");
        },
        // 2 -> 3: the drape coefficient in percent (it was a fraction 0..1), the
        // fit quality as the fit's reduced chi-square (`drape fit` presets had
        // none), presets rewritten in the typed format (unit-suffixed keys).
        rewrite_presets,
    };
    return m;
}

} // namespace

void migrate_schema(sqlite3* db, const std::string& path, std::int64_t from, int target)
{
    for (auto v = from; v < target; ++v) migrations().at(static_cast<std::size_t>(v))(db, path);
}

} // namespace drape::library
