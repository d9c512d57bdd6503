#include "engine/library/fabric_library.hpp"
#include "engine/core/clock.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/json_reader.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"
#include "engine/library/schema.hpp"
#include "engine/library/sqlite.hpp"

#include <sqlite3.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <functional>
#include <regex>

#include <unistd.h>

namespace drape::library {

using nlohmann::json;
using sql::exec;
using sql::pragma_int;
using sql::Stmt;
using sql::Transaction;

namespace {

constexpr const char* kLibraryFormat = "drapekit-fabric-library";

void validate_date(const std::string& d, const std::string& what)
{
    if (!is_iso_date(d))
        throw ParameterError(what + ": '" + printable(d) + "' is not an ISO 8601 date such as 2026-11-22 or 2026-11-22T10:30");
}

std::string like_pattern(const std::string& s)
{
    std::string out = "%";
    for (char c : s) {
        if (c == '%' || c == '_' || c == '\\') out += '\\';
        out += c;
    }
    return out + "%";
}

const char* const kColumns =
    "id, name, composition, format, areal_density, drape_coefficient, fit_quality, created, modified, revision, preset";

FabricRecord read_record(const Stmt& s, const std::string& path)
{
    FabricRecord r;
    r.id = s.integer(0);
    r.name = s.text(1);
    r.composition = s.text(2);
    r.format = s.text(3);
    r.areal_density_kg_m2 = s.real(4);
    r.drape_coefficient_percent = s.opt_real(5);
    r.fit_quality = s.opt_real(6);
    r.created = s.text(7);
    r.modified = s.text(8);
    r.revision = static_cast<int>(s.integer(9));
    const std::string where = path + ": fabric '" + r.name + "'";
    r.preset_json = parse_json(s.text(10), where + " (stored preset)");
    r.preset = fabric::fabric_from_json(r.preset_json, where);
    return r;
}

} // namespace

// ---------------------------------------------------------------- helpers

std::string default_library_path()
{
    if (const char* p = std::getenv("DRAPE_LIBRARY"); p && *p) return p;
    if (const char* x = std::getenv("XDG_DATA_HOME"); x && *x) return std::string(x) + "/drapekit/library.sqlite";
    if (const char* h = std::getenv("HOME"); h && *h) return std::string(h) + "/.local/share/drapekit/library.sqlite";
    return "drapekit-library.sqlite";
}

std::string normalize_name(const std::string& name) { return drape::normalize_name(name, "fabric name", kMaxNameChars); }

void validate_name(const std::string& name) { (void)normalize_name(name); }

bool is_iso_date(const std::string& d)
{
    static const std::regex re(R"(^\d{4}(-\d{2}(-\d{2}(T\d{2}(:\d{2}(:\d{2}Z?)?)?)?)?)?$)");
    return d.size() <= 32 && std::regex_match(d, re);
}

namespace {
/// "file:/abs/path?immutable=1" with the characters a URI path cannot hold percent-encoded.
std::string immutable_uri(const std::string& path)
{
    std::error_code ec;
    const std::string abs = std::filesystem::absolute(path, ec).string();
    std::string out = "file:";
    for (unsigned char c : ec ? path : abs) {
        if (c == '%' || c == '?' || c == '#' || c < 0x21 || c >= 0x7f) {
            char buf[4];
            std::snprintf(buf, sizeof buf, "%%%02X", c);
            out += buf;
        } else {
            out += static_cast<char>(c);
        }
    }
    return out + "?immutable=1";
}
} // namespace

// ---------------------------------------------------------------- library

FabricLibrary::FabricLibrary(const std::string& path, Mode mode) : m_path(path), m_mode(mode)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    // SQLite reads "" as a temporary and ":memory:" (or a "file:" URI) as a
    // database in memory: nothing would be stored where the user looks for it.
    if (path.empty()) throw ParameterError("fabric library: the path is empty");
    if (path == ":memory:" || path.rfind("file:", 0) == 0)
        throw ParameterError("fabric library: '" + path + "' is not a file path (a library must be stored in a file)");
    if (mode == Mode::ReadOnly) {
        if (!fs::exists(path, ec)) throw FileError(path + ": no fabric library at this path");
    } else if (const fs::path parent = fs::path(path).parent_path(); !parent.empty()) {
        fs::create_directories(parent, ec);
        if (ec) throw FileError(path + ": cannot create the folder " + parent.string() + " (" + ec.message() + ")");
    }
    if (fs::is_directory(path, ec)) throw FileError(path + ": is a folder, not a fabric library file");
    if (mode == Mode::ReadWrite && fs::exists(path, ec)) {
        if (::access(path.c_str(), W_OK) != 0)
            throw FileError(path + ": the fabric library is read-only (no permission to write the file); list, show and export "
                                   "read it, add/update/remove/import need a writable copy");
        // SQLite keeps its write-ahead log beside the library.
        const fs::path parent = fs::path(path).parent_path().empty() ? fs::path(".") : fs::path(path).parent_path();
        if (::access(parent.c_str(), W_OK) != 0)
            throw FileError(path + ": the folder " + parent.string() + " is read-only, and SQLite writes its journal beside the "
                                   "library; list, show and export read it, add/update/remove/import need a writable folder");
    }
    const int flags = mode == Mode::ReadOnly ? SQLITE_OPEN_READONLY : (SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE);
    auto open = [&](const std::string& name, int extra) {
        if (sqlite3_open_v2(name.c_str(), &m_db, flags | extra | SQLITE_OPEN_NOMUTEX, nullptr) != SQLITE_OK) {
            const std::string why = m_db ? sqlite3_errmsg(m_db) : "out of memory";
            sqlite3_close(m_db);
            m_db = nullptr;
            throw FileError(path + ": cannot open the fabric library (" + why + ")");
        }
        sqlite3_busy_timeout(m_db, 10000);
    };
    open(path, 0);
    try {
        // The first read tells a SQLite file from anything else (SQLITE_NOTADB).
        try {
            pragma_int(m_db, m_path, "application_id");
        } catch (const sql::DatabaseError& e) {
            // A library in WAL mode needs its -shm file to be read; in a folder
            // the user cannot write, SQLite cannot create it. Nobody can write
            // the library there either, so it is read as an immutable file.
            if (mode != Mode::ReadOnly || (e.primary_code() != SQLITE_CANTOPEN && e.primary_code() != SQLITE_READONLY)) throw;
            sqlite3_close(m_db);
            m_db = nullptr;
            open(immutable_uri(path), SQLITE_OPEN_URI);
            pragma_int(m_db, m_path, "application_id");
        }
        if (mode == Mode::ReadWrite) {
            exec(m_db, m_path, "PRAGMA journal_mode=WAL");
            exec(m_db, m_path, "PRAGMA synchronous=FULL");
        } else {
            exec(m_db, m_path, "PRAGMA query_only=1");
        }
        migrate();
    } catch (const sql::DatabaseError& e) {
        sqlite3_close(m_db);
        m_db = nullptr;
        if (e.primary_code() == SQLITE_NOTADB)
            throw FileError(path + ": not a fabric library (not a SQLite database, or a damaged one)");
        throw;
    } catch (...) {
        sqlite3_close(m_db);
        m_db = nullptr;
        throw;
    }
}

FabricLibrary::~FabricLibrary()
{
    if (m_db) sqlite3_close(m_db);
}

FabricLibrary::FabricLibrary(FabricLibrary&& o) noexcept : m_db(o.m_db), m_path(std::move(o.m_path)), m_mode(o.m_mode)
{
    o.m_db = nullptr;
}

FabricLibrary& FabricLibrary::operator=(FabricLibrary&& o) noexcept
{
    if (this != &o) {
        if (m_db) sqlite3_close(m_db);
        m_db = o.m_db;
        m_path = std::move(o.m_path);
        m_mode = o.m_mode;
        o.m_db = nullptr;
    }
    return *this;
}

int FabricLibrary::schema_version() const { return static_cast<int>(pragma_int(m_db, m_path, "user_version")); }

void FabricLibrary::migrate()
{
    const bool write = m_mode == Mode::ReadWrite;
    Transaction tx(m_db, m_path, write);
    const auto version = pragma_int(m_db, m_path, "user_version");
    const auto app = pragma_int(m_db, m_path, "application_id");
    std::int64_t tables = 0;
    {
        Stmt s(m_db, m_path, "SELECT count(*) FROM sqlite_master");
        if (s.step()) tables = s.integer(0);
    }
    if (app != kApplicationId && (app != 0 || tables > 0))
        throw FileError(m_path + ": not a fabric library (a SQLite database of another application)");
    if (version > kSchemaVersion)
        throw FileError(m_path + ": written by a newer Drapekit (schema version " + std::to_string(version) +
                        ", this build reads up to " + std::to_string(kSchemaVersion) + ")");
    if (version == kSchemaVersion) {
        tx.commit();
        return;
    }
    if (!write && tables == 0)
        throw FileError(m_path + ": an empty file, not a fabric library yet (drape library add or import with --library " +
                        m_path + " makes it one)");
    if (!write)
        throw FileError(m_path + ": schema version " + std::to_string(version) + " needs migrating to " +
                        std::to_string(kSchemaVersion) + "; open it read-write once (e.g. drape library add)");
    migrate_schema(m_db, m_path, version, kSchemaVersion);
    exec(m_db, m_path, "PRAGMA application_id=" + std::to_string(kApplicationId));
    exec(m_db, m_path, "PRAGMA user_version=" + std::to_string(kSchemaVersion));
    tx.commit();
}

std::int64_t FabricLibrary::put(const fabric::FabricPreset& in, const std::string& name_in, OnConflict on_conflict,
                                ImportReport* report, const std::string& created)
{
    const std::string& raw = name_in.empty() ? in.name : name_in;
    std::string name = normalize_name(raw);
    fabric::FabricPreset preset = in;

    std::int64_t existing = -1; // row id of a fabric with this name, -1 when none
    for (const std::string* n : {static_cast<const std::string*>(&name), &raw}) { // the raw spelling: a row stored before names were normalised
        Stmt s(m_db, m_path, "SELECT id FROM fabrics WHERE name = ?1");
        s.bind(1, *n);
        if (s.step()) {
            existing = s.integer(0);
            break;
        }
    }
    if (existing >= 0) {
        switch (on_conflict) {
        case OnConflict::Fail:
            throw ParameterError(m_path + ": a fabric named '" + name + "' already exists");
        case OnConflict::Skip:
            if (report) {
                ++report->skipped;
                report->names.push_back(name);
            }
            return existing;
        case OnConflict::Rename: {
            const std::string base = name;
            for (int k = 2;; ++k) {
                name = base + " (" + std::to_string(k) + ")";
                Stmt s(m_db, m_path, "SELECT 1 FROM fabrics WHERE name = ?1");
                s.bind(1, name);
                if (!s.step()) break;
            }
            existing = -1;
            if (report) ++report->renamed;
            break;
        }
        case OnConflict::Replace:
            break;
        }
    }
    preset.name = name;
    const json j = fabric::fabric_to_json(preset);
    // What is stored must read back: the same check a later read applies.
    const fabric::FabricPreset check = fabric::fabric_from_json(j, m_path + ": fabric '" + name + "'");
    const Columns d = derive_columns(check);
    const std::string now = utc_now();
    std::int64_t id = 0;
    if (existing >= 0) {
        Stmt u(m_db, m_path,
               "UPDATE fabrics SET preset = ?1, format = ?2, composition = ?3, areal_density = ?4, drape_coefficient = ?5,"
               " fit_quality = ?6, modified = ?7, revision = revision + 1, name = ?9 WHERE id = ?8");
        u.bind(1, j.dump()).bind(2, d.format).bind(3, d.composition).bind(4, d.weight).bind(5, d.drape_percent).bind(6, d.fit_quality);
        u.bind(7, now).bind(8, existing).bind(9, name);
        u.run();
        id = existing;
        if (report) ++report->replaced;
    } else {
        Stmt s(m_db, m_path,
               "INSERT INTO fabrics (name, preset, format, composition, areal_density, drape_coefficient, fit_quality,"
               " created, modified, revision) VALUES (?1, ?2, ?3, ?4, ?5, ?6, ?7, ?8, ?10, 1)");
        s.bind(1, name).bind(2, j.dump()).bind(3, d.format).bind(4, d.composition).bind(5, d.weight).bind(6, d.drape_percent);
        s.bind(7, d.fit_quality).bind(8, created.empty() ? now : created).bind(10, now);
        s.run();
        id = sqlite3_last_insert_rowid(m_db);
        if (report) ++report->added;
    }
    if (report) report->names.push_back(name);
    return id;
}

std::int64_t FabricLibrary::add(const fabric::FabricPreset& preset, const std::string& name)
{
    Transaction tx(m_db, m_path, true);
    const auto id = put(preset, name, OnConflict::Fail, nullptr);
    tx.commit();
    return id;
}

void FabricLibrary::update(const std::string& name_in, const fabric::FabricPreset& preset)
{
    Transaction tx(m_db, m_path, true);
    const std::string name = stored_name(name_in);
    {
        Stmt s(m_db, m_path, "SELECT name FROM fabrics WHERE name = ?1");
        s.bind(1, name);
        if (!s.step()) throw NotFoundError(m_path + ": no fabric named '" + printable(name_in) + "'");
    }
    put(preset, name, OnConflict::Replace, nullptr);
    tx.commit();
}

void FabricLibrary::rename(const std::string& from_in, const std::string& to_in)
{
    const std::string to = normalize_name(to_in);
    Transaction tx(m_db, m_path, true);
    const std::string from = stored_name(from_in);
    FabricRecord r;
    {
        Stmt s(m_db, m_path, std::string("SELECT ") + kColumns + " FROM fabrics WHERE name = ?1");
        s.bind(1, from);
        if (!s.step()) throw NotFoundError(m_path + ": no fabric named '" + printable(from_in) + "'");
        r = read_record(s, m_path);
    }
    {
        Stmt s(m_db, m_path, "SELECT id FROM fabrics WHERE name = ?1");
        s.bind(1, to);
        if (s.step() && s.integer(0) != r.id) throw ParameterError(m_path + ": a fabric named '" + to + "' already exists");
    }
    r.preset.name = to;
    Stmt u(m_db, m_path, "UPDATE fabrics SET name = ?1, preset = ?2, modified = ?3, revision = revision + 1 WHERE id = ?4");
    u.bind(1, to).bind(2, fabric::fabric_to_json(r.preset).dump()).bind(3, utc_now()).bind(4, r.id);
    u.run();
    tx.commit();
}

void FabricLibrary::remove(const std::string& name) { remove(std::vector<std::string>{name}); }

void FabricLibrary::remove(const std::vector<std::string>& names)
{
    Transaction tx(m_db, m_path, true);
    for (const auto& name : names) {
        Stmt s(m_db, m_path, "DELETE FROM fabrics WHERE name = ?1");
        s.bind(1, stored_name(name));
        s.run();
        if (sqlite3_changes(m_db) == 0)
            throw NotFoundError(m_path + ": no fabric named '" + printable(name) + "'" + (names.size() > 1 ? "; nothing was removed" : ""));
    }
    tx.commit();
}

std::string FabricLibrary::stored_name(const std::string& name) const
{
    // Names are stored normalised; a name stored before that rule (with a
    // trailing no-break space, say) is still found by its own spelling.
    const auto n = try_normalize_name(name, kMaxNameChars);
    if (n && *n != name) {
        Stmt s(m_db, m_path, "SELECT name FROM fabrics WHERE name = ?1");
        s.bind(1, *n);
        if (s.step()) return s.text(0);
    }
    return name;
}

std::optional<FabricRecord> FabricLibrary::find(const std::string& name) const
{
    Stmt s(m_db, m_path, std::string("SELECT ") + kColumns + " FROM fabrics WHERE name = ?1");
    s.bind(1, stored_name(name));
    if (!s.step()) return std::nullopt;
    return read_record(s, m_path);
}

FabricRecord FabricLibrary::get(const std::string& name) const
{
    auto r = find(name);
    if (!r) throw NotFoundError(m_path + ": no fabric named '" + printable(name) + "'");
    return std::move(*r);
}

int FabricLibrary::count() const
{
    Stmt s(m_db, m_path, "SELECT count(*) FROM fabrics");
    return s.step() ? static_cast<int>(s.integer(0)) : 0;
}

std::vector<FabricRecord> FabricLibrary::list(const Filter& f) const
{
    std::string sql = std::string("SELECT ") + kColumns + " FROM fabrics WHERE 1";
    std::vector<std::function<void(Stmt&, int)>> binds;
    auto add_text = [&](const std::string& clause, const std::string& value) {
        sql += " AND " + clause;
        binds.push_back([value](Stmt& s, int i) { s.bind(i, value); });
    };
    auto add_real = [&](const std::string& clause, double value, const char* what) {
        if (!std::isfinite(value)) throw ParameterError(std::string("filter ") + what + ": not a finite number");
        sql += " AND " + clause;
        binds.push_back([value](Stmt& s, int i) { s.bind(i, value); });
    };
    if (!f.text.empty()) {
        const std::string p = like_pattern(f.text);
        sql += " AND (name LIKE ? ESCAPE '\\' OR composition LIKE ? ESCAPE '\\' OR"
               " ifnull(json_extract(preset, '$.source'), '') LIKE ? ESCAPE '\\' OR"
               " ifnull(json_extract(preset, '$.notes'), '') LIKE ? ESCAPE '\\')";
        for (int k = 0; k < 4; ++k) binds.push_back([p](Stmt& s, int i) { s.bind(i, p); });
    }
    if (!f.name.empty()) add_text("name LIKE ? ESCAPE '\\'", like_pattern(f.name));
    if (!f.composition.empty()) add_text("composition LIKE ? ESCAPE '\\'", like_pattern(f.composition));
    if (f.weight_min) add_real("areal_density >= ?", *f.weight_min, "weight");
    if (f.weight_max) add_real("areal_density <= ?", *f.weight_max, "weight");
    if (f.drape_min) add_real("drape_coefficient >= ?", *f.drape_min, "D");
    if (f.drape_max) add_real("drape_coefficient <= ?", *f.drape_max, "D");
    if (f.fit_min) add_real("fit_quality >= ?", *f.fit_min, "fit quality");
    if (f.fit_max) add_real("fit_quality <= ?", *f.fit_max, "fit quality");
    // Prefix comparison makes a bare date inclusive of its whole day.
    if (!f.modified_from.empty()) {
        validate_date(f.modified_from, "filter modified from");
        sql += " AND substr(modified, 1, length(?)) >= ?";
        binds.push_back([v = f.modified_from](Stmt& s, int i) { s.bind(i, v); });
        binds.push_back([v = f.modified_from](Stmt& s, int i) { s.bind(i, v); });
    }
    if (!f.modified_to.empty()) {
        validate_date(f.modified_to, "filter modified to");
        sql += " AND substr(modified, 1, length(?)) <= ?";
        binds.push_back([v = f.modified_to](Stmt& s, int i) { s.bind(i, v); });
        binds.push_back([v = f.modified_to](Stmt& s, int i) { s.bind(i, v); });
    }
    const char* key = "name COLLATE NOCASE";
    switch (f.sort) {
    case SortKey::Name: break;
    case SortKey::Weight: key = "areal_density"; break;
    case SortKey::DrapeCoefficient: key = "drape_coefficient"; break;
    case SortKey::Modified: key = "modified"; break;
    case SortKey::FitQuality: key = "fit_quality"; break;
    }
    sql += std::string(" ORDER BY ") + key + (f.descending ? " DESC" : " ASC") + " NULLS LAST, name COLLATE NOCASE";
    if (f.limit > 0) sql += " LIMIT " + std::to_string(f.limit);

    Stmt s(m_db, m_path, sql);
    for (std::size_t i = 0; i < binds.size(); ++i) binds[i](s, static_cast<int>(i + 1));
    std::vector<FabricRecord> out;
    while (s.step()) out.push_back(read_record(s, m_path));
    return out;
}

json FabricLibrary::export_preset(const std::string& name, PresetFormat format) const
{
    const FabricRecord r = get(name);
    if (format == PresetFormat::Drapekit) return r.preset_json;
    if (r.preset.seed) {
        json j = fabric::seed_to_json(*r.preset.seed);
        j["name"] = r.name;
        return j;
    }
    throw ParameterError(m_path + ": fabric '" + name +
                         "' holds continuum parameters; the seed's 19 grid constants describe one particular grid and "
                         "have no bending counterpart, so it is exported as drapekit-fabric only");
}

std::int64_t FabricLibrary::import_preset(const json& j, const std::string& where, const std::string& name,
                                          OnConflict on_conflict)
{
    const fabric::FabricPreset p = fabric::fabric_from_json(j, where);
    Transaction tx(m_db, m_path, true);
    const auto id = put(p, name, on_conflict, nullptr);
    tx.commit();
    return id;
}

json FabricLibrary::export_all() const
{
    // One read transaction: a writer committing meanwhile is either wholly in or wholly out.
    Transaction tx(m_db, m_path, false);
    json doc;
    doc["format"] = kLibraryFormat;
    doc["version"] = 1;
    doc["exported"] = utc_now();
    doc["fabrics"] = json::array();
    Stmt s(m_db, m_path, std::string("SELECT ") + kColumns + " FROM fabrics ORDER BY name COLLATE NOCASE");
    while (s.step()) {
        const FabricRecord r = read_record(s, m_path);
        doc["fabrics"].push_back({{"name", r.name},
                                  {"created", r.created},
                                  {"modified", r.modified},
                                  {"revision", r.revision},
                                  {"preset", r.preset_json}});
    }
    tx.commit();
    return doc;
}

ImportReport FabricLibrary::import_all(const json& doc, const std::string& where, OnConflict on_conflict)
{
    const json* list = nullptr;
    if (doc.is_array()) {
        list = &doc;
    } else if (doc.is_object() && doc.contains("format") && doc["format"] == kLibraryFormat) {
        if (doc.contains("version") && doc["version"] != 1)
            throw ParameterError(where + ": field 'version' = " + describe_json(doc["version"]) + " is not supported (reads 1)");
        if (!doc.contains("fabrics") || !doc["fabrics"].is_array())
            throw ParameterError(where + ": missing array field 'fabrics'");
        list = &doc["fabrics"];
    } else {
        throw ParameterError(where + ": field 'format' = " +
                             (doc.is_object() && doc.contains("format") ? describe_json(doc["format"]) : std::string("(missing)")) +
                             " must be \"" + std::string(kLibraryFormat) + "\" (or the document a JSON array of presets)");
    }
    // Parse everything before touching the database, so a bad entry names
    // itself and nothing is written.
    struct Item {
        fabric::FabricPreset preset;
        std::string name, created;
    };
    std::vector<Item> items;
    for (std::size_t i = 0; i < list->size(); ++i) {
        const json& e = (*list)[i];
        const std::string w = where + ": fabrics[" + std::to_string(i) + "]";
        if (!e.is_object()) throw ParameterError(w + ": not a JSON object");
        const bool wrapped = e.contains("preset");
        std::string name;
        if (wrapped && e.contains("name")) {
            if (!e["name"].is_string()) throw ParameterError(w + ": field 'name' is not a string");
            name = e["name"].get<std::string>();
        }
        // The exporting library's creation date travels with the fabric (an
        // ISO 8601 UTC time as export_all writes it); anything else is refused.
        std::string created;
        if (wrapped && e.contains("created")) {
            const json& c = e["created"];
            if (!c.is_string() || !is_iso_date(c.get<std::string>()))
                throw ParameterError(w + ": field 'created' = " + describe_json(c) + " is not an ISO 8601 date such as 2026-11-22T01:02:03Z");
            created = c.get<std::string>();
        }
        items.push_back({fabric::fabric_from_json(wrapped ? e["preset"] : e, w), name, created});
    }
    ImportReport report;
    Transaction tx(m_db, m_path, true);
    for (const auto& it : items) put(it.preset, it.name, on_conflict, &report, it.created);
    tx.commit();
    return report;
}

void FabricLibrary::limit_pages_for_testing(std::int64_t pages)
{
    pragma_int(m_db, m_path, "max_page_count=" + std::to_string(pages));
}

} // namespace drape::library
