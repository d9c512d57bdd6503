// Fabric library: add/update/rename/delete, search and filters, preset
// formats, bulk export/import, migrations, bad files and a full disk.
#include "engine/core/error.hpp"
#include "engine/fabric/preset.hpp"
#include "engine/library/fabric_library.hpp"

#include <sqlite3.h>

#include <QTemporaryDir>
#include <QTest>
#include <QtCore/qfloat16.h> // QCOMPARE on json values considers the qfloat16 overload: complete it

#include <filesystem>
#include <fstream>

using namespace drape;
using namespace drape::library;
using nlohmann::json;

namespace {

fabric::FabricPreset make_preset(const std::string& name, double rho, const std::string& composition,
                                std::optional<double> D = std::nullopt, std::optional<double> fit = std::nullopt) // D [%]
{
    fabric::FabricPreset p;
    p.name = name;
    p.params[cloth::Param::AreaDensity] = rho;
    p.params[cloth::Param::BendWarp] = 2e-6;
    p.composition = composition;
    p.source = "unit test";
    if (D) {
        p.drape = fabric::DrapeReference{};
        p.drape->percent = *D;
    }
    if (fit) {
        p.fit = fabric::FitSummary{};
        p.fit->reduced_chi2 = *fit;
    }
    return p;
}

std::vector<std::string> names(const std::vector<FabricRecord>& v)
{
    std::vector<std::string> out;
    for (const auto& r : v) out.push_back(r.name);
    return out;
}

void raw_exec(const std::string& path, const std::string& sql)
{
    sqlite3* db = nullptr;
    QCOMPARE(sqlite3_open(path.c_str(), &db), SQLITE_OK);
    char* err = nullptr;
    const int rc = sqlite3_exec(db, sql.c_str(), nullptr, nullptr, &err);
    if (rc != SQLITE_OK) qWarning("sqlite: %s", err ? err : "?");
    sqlite3_free(err);
    sqlite3_close(db);
    QCOMPARE(rc, SQLITE_OK);
}

template <class F>
QString expect_file_error(const std::string& path, F&& f)
{
    try {
        f();
    } catch (const FileError& e) {
        const QString msg = QString::fromStdString(e.what());
        if (!msg.contains(QString::fromStdString(path))) return "message does not name the file: " + msg;
        return {};
    } catch (const std::exception& e) {
        return QString("wrong exception type: ") + e.what();
    }
    return "no exception";
}

} // namespace

class TestFabricLibrary : public QObject {
    Q_OBJECT
    QTemporaryDir m_dir;
    std::string tmp(const char* name) const { return m_dir.filePath(name).toStdString(); }

private slots:
    void createsSchemaInWalMode()
    {
        const std::string path = tmp("sub/dir/lib.sqlite"); // the folder is created
        FabricLibrary lib(path);
        QCOMPARE(lib.schema_version(), FabricLibrary::kSchemaVersion);
        QCOMPARE(lib.count(), 0);
        sqlite3* db = nullptr;
        QCOMPARE(sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
        sqlite3_stmt* s = nullptr;
        sqlite3_prepare_v2(db, "PRAGMA journal_mode", -1, &s, nullptr);
        QCOMPARE(sqlite3_step(s), SQLITE_ROW);
        QCOMPARE(QString(reinterpret_cast<const char*>(sqlite3_column_text(s, 0))), QString("wal"));
        sqlite3_finalize(s);
        sqlite3_prepare_v2(db, "PRAGMA application_id", -1, &s, nullptr);
        QCOMPARE(sqlite3_step(s), SQLITE_ROW);
        QCOMPARE(sqlite3_column_int(s, 0), FabricLibrary::kApplicationId);
        sqlite3_finalize(s);
        sqlite3_close(db);
    }

    void addUpdateRenameRemove()
    {
        FabricLibrary lib(tmp("crud.sqlite"));
        lib.add(make_preset("Cotton A", 0.15, "100 % cotton", 65, 0.002));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(make_preset("cotton a", 0.2, "x"))); // names are case-insensitive
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(make_preset("", 0.2, "x")));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(make_preset(" \t", 0.2, "x")));
        // Names are stored trimmed (a no-break space too): " Cotton A\u00a0" is "Cotton A".
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(make_preset(" Cotton A\u00a0", 0.2, "x")));
        // Out-of-range parameters are refused before anything is written.
        fabric::FabricPreset bad = make_preset("bad", 0.2, "x");
        bad.params[cloth::Param::AreaDensity] = 50.0;
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(bad));
        QCOMPARE(lib.count(), 1);

        FabricRecord r = lib.get("Cotton A");
        QCOMPARE(r.composition, std::string("100 % cotton"));
        QCOMPARE(r.areal_density_kg_m2, 0.15);
        QCOMPARE(*r.drape_coefficient_percent, 65.0);
        QCOMPARE(*r.fit_quality, 0.002);
        QCOMPARE(r.revision, 1);
        QCOMPARE(r.format, std::string("drapekit-fabric"));
        QCOMPARE(r.preset.params[cloth::Param::BendWarp], 2e-6);
        QCOMPARE(r.preset_json["source"].get<std::string>(), std::string("unit test"));

        lib.update("Cotton A", make_preset("ignored", 0.18, "cotton/elastane", 70));
        r = lib.get("Cotton A");
        QCOMPARE(r.revision, 2);
        QCOMPARE(r.areal_density_kg_m2, 0.18);
        QCOMPARE(r.composition, std::string("cotton/elastane"));
        QVERIFY(!r.fit_quality);
        QCOMPARE(fabric::fabric_from_json(r.preset_json, "x").composition, std::string("cotton/elastane"));
        QCOMPARE(r.preset.name, std::string("Cotton A"));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.update("nope", make_preset("n", 0.1, "")));

        lib.add(make_preset("Silk", 0.06, "silk"));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.rename("Silk", "COTTON A"));
        lib.rename("Cotton A", "Cotton B");
        QVERIFY(!lib.find("Cotton A"));
        r = lib.get("Cotton B");
        QCOMPARE(r.revision, 3);
        QCOMPARE(r.preset_json["name"].get<std::string>(), std::string("Cotton B")); // preset renamed too
        lib.rename("Silk", "silk"); // case change of the same fabric is allowed
        QVERIFY(lib.find("silk"));

        lib.remove("Cotton B");
        QVERIFY(!lib.find("Cotton B"));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.remove("Cotton B"));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.get("Cotton B"));
        QCOMPARE(lib.count(), 1);
    }

    void searchAndFilter()
    {
        FabricLibrary lib(tmp("filter.sqlite"));
        lib.add(make_preset("Silk crepe", 0.06, "100 % silk", 31, 0.004));
        lib.add(make_preset("Cotton poplin", 0.12, "100 % cotton", 68, 0.002));
        lib.add(make_preset("Denim 12oz", 0.41, "cotton", 82));
        lib.add(make_preset("Wool worsted", 0.22, "wool", 55, 0.003));
        fabric::FabricPreset noted = make_preset("Mystery", 0.3, "");
        noted.notes = "bought in Szeged";
        lib.add(noted);

        using V = std::vector<std::string>;
        QCOMPARE(names(lib.list()), (V{"Cotton poplin", "Denim 12oz", "Mystery", "Silk crepe", "Wool worsted"}));
        Filter f;
        f.composition = "COTTON";
        QCOMPARE(names(lib.list(f)), (V{"Cotton poplin", "Denim 12oz"}));
        f = {};
        f.name = "o";
        f.weight_min = 0.1;
        f.weight_max = 0.3;
        QCOMPARE(names(lib.list(f)), (V{"Cotton poplin", "Wool worsted"}));
        f = {};
        f.drape_min = 50;
        f.drape_max = 70;
        QCOMPARE(names(lib.list(f)), (V{"Cotton poplin", "Wool worsted"}));
        f = {};
        f.fit_max = 0.0035; // records without a fit drop out
        QCOMPARE(names(lib.list(f)), (V{"Cotton poplin", "Wool worsted"}));
        f = {};
        f.text = "szeged"; // in the notes
        QCOMPARE(names(lib.list(f)), (V{"Mystery"}));
        f = {};
        f.text = "silk"; // name or composition
        QCOMPARE(names(lib.list(f)), (V{"Silk crepe"}));
        f = {};
        f.text = "100 %"; // LIKE wildcards are literal
        QCOMPARE(names(lib.list(f)), (V{"Cotton poplin", "Silk crepe"}));
        f = {};
        f.sort = SortKey::Weight;
        f.descending = true;
        f.limit = 2;
        QCOMPARE(names(lib.list(f)), (V{"Denim 12oz", "Mystery"}));
        f = {};
        f.sort = SortKey::DrapeCoefficient; // missing D sorts last
        QCOMPARE(names(lib.list(f)), (V{"Silk crepe", "Wool worsted", "Cotton poplin", "Denim 12oz", "Mystery"}));
        // Dates: today's date includes everything just written; a past range nothing.
        const std::string today = lib.get("Mystery").modified.substr(0, 10);
        f = {};
        f.modified_from = today;
        f.modified_to = today;
        QCOMPARE(lib.list(f).size(), std::size_t(5));
        f.modified_from = "2001-01-01";
        f.modified_to = "2001-12-31";
        QCOMPARE(lib.list(f).size(), std::size_t(0));
        f.modified_to = "yesterday";
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.list(f));
    }

    void seedFormatImportExport()
    {
        FabricLibrary lib(tmp("seed.sqlite"));
        fabric::SeedParams s = fabric::SeedParams::table1();
        s.sst_ku = 175.5;
        json j = fabric::seed_to_json(s);
        j["name"] = "Seed fabric";
        j["composition"] = "unknown";
        lib.import_preset(j, "seed.json");
        const FabricRecord r = lib.get("Seed fabric");
        QCOMPARE(r.format, std::string("seed-19"));
        QCOMPARE(r.composition, std::string("unknown"));
        // Weight by the engine's own mapping of the seed's constants, so the
        // library and the simulator agree on what the preset weighs.
        const double expected = fabric::continuum_from_seed(s)[cloth::Param::AreaDensity];
        QVERIFY(expected > 0);
        QVERIFY(std::abs(r.areal_density_kg_m2 - expected) < 1e-12 * expected);
        const json out = lib.export_preset("Seed fabric", PresetFormat::Seed19);
        const fabric::SeedParams back = fabric::seed_from_json(out, "export");
        QCOMPARE(back.sst_ku, 175.5);
        QCOMPARE(back.ssh_d, s.ssh_d);
        QCOMPARE(back.u, s.u);
        QCOMPARE(out["format"].get<std::string>(), std::string("seed-19"));
        // A continuum preset has no exact seed-19 form: refused, with a reason.
        lib.add(make_preset("Continuum", 0.2, ""));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.export_preset("Continuum", PresetFormat::Seed19));
        const json dk = lib.export_preset("Continuum");
        QCOMPARE(dk["format"].get<std::string>(), std::string("drapekit-fabric"));
        QCOMPARE(dk["parameters"]["areal_density_kg_m2"].get<double>(), 0.2);
        // Bad preset JSON names the field.
        json broken = dk;
        broken["parameters"]["shear_N_m"] = "stiff";
        try {
            lib.import_preset(broken, "broken.json", "Broken");
            QFAIL("no exception");
        } catch (const ParameterError& e) {
            QVERIFY(QString(e.what()).contains("broken.json"));
            QVERIFY(QString(e.what()).contains("shear_N_m"));
        }
        QVERIFY(!lib.find("Broken"));
    }

    void bulkExportImportRoundTrip()
    {
        FabricLibrary a(tmp("bulk-a.sqlite"));
        a.add(make_preset("One", 0.1, "linen", 0.5));
        a.add(make_preset("Two", 0.2, "viscose"));
        json seed = fabric::seed_to_json(fabric::SeedParams::table1());
        seed["name"] = "Three";
        a.import_preset(seed, "seed");
        const json doc = a.export_all();
        QCOMPARE(doc["format"].get<std::string>(), std::string("drapekit-fabric-library"));
        QCOMPARE(doc["fabrics"].size(), std::size_t(3));

        FabricLibrary b(tmp("bulk-b.sqlite"));
        const ImportReport rep = b.import_all(doc, "doc");
        QCOMPARE(rep.added, 3);
        for (const char* n : {"One", "Two", "Three"}) QCOMPARE(b.get(n).preset_json, a.get(n).preset_json);
        // The creation date travels with the fabric (it was "now" at import until
        // 2026-11-30: the test passed only when both fell in the same second).
        QCOMPARE(b.get("One").created, a.get("One").created);
        {
            json bad = doc;
            bad["fabrics"][1]["created"] = 42;
            FabricLibrary c(tmp("bulk-c.sqlite"));
            try {
                c.import_all(bad, "bad.json");
                QFAIL("no exception");
            } catch (const ParameterError& e) {
                QVERIFY2(QString(e.what()).contains("bad.json: fabrics[1]: field 'created' = number 42"), e.what());
            }
            QCOMPARE(c.count(), 0);
        }

        // Conflicts: fail (nothing written), skip, rename, replace.
        json doc2 = doc;
        doc2["fabrics"][0]["preset"]["composition"] = "hemp";
        QVERIFY_THROWS_EXCEPTION(ParameterError, b.import_all(doc2, "doc2"));
        QCOMPARE(b.count(), 3);
        QCOMPARE(b.import_all(doc2, "doc2", OnConflict::Skip).skipped, 3);
        QCOMPARE(b.get("One").composition, std::string("linen"));
        const ImportReport ren = b.import_all(doc2, "doc2", OnConflict::Rename);
        QCOMPARE(ren.renamed, 3);
        QCOMPARE(b.get("One (2)").composition, std::string("hemp"));
        const ImportReport rep2 = b.import_all(doc2, "doc2", OnConflict::Replace);
        QCOMPARE(rep2.replaced, 3);
        QCOMPARE(b.get("One").composition, std::string("hemp"));
        QCOMPARE(b.get("One").revision, 2);
        QCOMPARE(b.count(), 6);

        // One bad entry: the whole import is refused and nothing is written.
        json doc3 = doc;
        doc3["fabrics"][0]["name"] = "Fresh";
        doc3["fabrics"][2]["preset"]["parameters"]["thickness_m"] = -1.0; // "Two" (sorted: One, Three, Two)
        QVERIFY_THROWS_EXCEPTION(ParameterError, b.import_all(doc3, "doc3", OnConflict::Replace));
        QVERIFY(!b.find("Fresh"));
        QVERIFY_THROWS_EXCEPTION(ParameterError, b.import_all(json{{"format", "other"}}, "doc4"));
    }

    /// A preset `drape fit` wrote before the typed format (the 2026-11-22
    /// docs/fit-report preset, kept in tests/library/data; keys before the
    /// unit-suffix rule) loads, and enters the library with its fit
    /// quality (the reduced chi-square) - the library used to look for fields
    /// the fit never wrote.
    void fittedPresetShowsItsFitQuality()
    {
        const fabric::FabricPreset p = fabric::load_fabric(DRAPE_SOURCE_DIR "/tests/library/data/DL-A08-legacy.fabric.json");
        QVERIFY(p.fit.has_value() && p.fit->reduced_chi2.has_value());
        QVERIFY(p.provenance.has_value());
        QCOMPARE(p.provenance->grid, 25);
        QCOMPARE(p.provenance->tool, std::string("drape fit"));
        QVERIFY(p.params[cloth::Param::BendWarp] > 0);
        FabricLibrary lib(tmp("fitted.sqlite"));
        lib.add(p, "DL-A08 fit");
        const FabricRecord r = lib.get("DL-A08 fit");
        QVERIFY(r.fit_quality.has_value());
        QVERIFY(std::abs(*r.fit_quality - *p.fit->reduced_chi2) < 1e-12);
        QVERIFY(std::abs(*r.fit_quality - 45.06366551784406 / 65) < 1e-9); // chi2 / dof as the fit reported them
    }

    void migratesVersion1()
    {
        // A library as schema version 1 wrote it: presets only, no derived columns.
        const std::string path = tmp("v1.sqlite");
        // The preset as Drapekit wrote it then: D as a fraction, keys without the unit-suffix rule.
        const std::string text = R"({"format":"drapekit-fabric","version":1,"name":"Old cotton",)"
                                 R"("parameters":{"areal_density_kg_m2":0.14,"bend_warp_N_m":2e-6},)"
                                 R"("composition":"cotton","drape_coefficient":0.66,"fit":{"quality":0.5}})";
        std::string quoted;
        for (char c : text) quoted += c == '\'' ? std::string("''") : std::string(1, c);
        raw_exec(path, "PRAGMA journal_mode=WAL;"
                       "CREATE TABLE fabrics (id INTEGER PRIMARY KEY, name TEXT NOT NULL UNIQUE COLLATE NOCASE,"
                       " preset TEXT NOT NULL, created TEXT NOT NULL, modified TEXT NOT NULL);"
                       "INSERT INTO fabrics (name, preset, created, modified) VALUES ('Old cotton', '" +
                           quoted + "', '2020-05-01T10:00:00Z', '2020-05-01T10:00:00Z');"
                                    "PRAGMA application_id=" + std::to_string(FabricLibrary::kApplicationId) + ";"
                                    "PRAGMA user_version=1;");
        // Read-only cannot migrate and says so.
        QCOMPARE(expect_file_error(path, [&] { FabricLibrary ro(path, FabricLibrary::Mode::ReadOnly); }), QString());
        FabricLibrary lib(path);
        QCOMPARE(lib.schema_version(), 3);
        const FabricRecord r = lib.get("Old cotton");
        QCOMPARE(r.areal_density_kg_m2, 0.14);
        QCOMPARE(r.composition, std::string("cotton"));
        QVERIFY(std::abs(*r.drape_coefficient_percent - 66.0) < 1e-9);
        QCOMPARE(*r.fit_quality, 0.5);
        QCOMPARE(r.preset.params[cloth::Param::BendWarp], 2e-6);
        // The stored preset is rewritten in today's format.
        QVERIFY(r.preset_json["parameters"].contains("bend_warp_Nm"));
        QVERIFY(std::abs(r.preset_json["drape_coefficient"]["percent"].get<double>() - 66.0) < 1e-9);
        QCOMPARE(r.created, std::string("2020-05-01T10:00:00Z"));
        Filter f;
        f.modified_to = "2020-12";
        QCOMPARE(names(lib.list(f)), std::vector<std::string>{"Old cotton"});
    }

    void badFiles()
    {
        // Not a database at all.
        const std::string text = tmp("notes.sqlite");
        std::ofstream(text) << "these are my notes, not a database, but long enough to look like a file header.....\n";
        QCOMPARE(expect_file_error(text, [&] { FabricLibrary l(text); }), QString());
        // Another application's SQLite database.
        const std::string other = tmp("other.sqlite");
        raw_exec(other, "CREATE TABLE accounts (id INTEGER);");
        QCOMPARE(expect_file_error(other, [&] { FabricLibrary l(other); }), QString());
        // A newer schema.
        const std::string newer = tmp("newer.sqlite");
        { FabricLibrary l(newer); }
        raw_exec(newer, "PRAGMA user_version=99;");
        QCOMPARE(expect_file_error(newer, [&] { FabricLibrary l(newer); }), QString());
        // Missing in read-only mode (and not created).
        const std::string missing = tmp("missing.sqlite");
        QCOMPARE(expect_file_error(missing, [&] { FabricLibrary l(missing, FabricLibrary::Mode::ReadOnly); }), QString());
        QVERIFY(!std::filesystem::exists(missing));
        // A folder.
        QCOMPARE(expect_file_error(m_dir.path().toStdString(), [&] { FabricLibrary l(m_dir.path().toStdString()); }), QString());
        // A truncated library: opening or reading fails with FileError, never a crash.
        const std::string trunc = tmp("trunc.sqlite");
        {
            FabricLibrary l(trunc);
            for (int i = 0; i < 60; ++i) {
                fabric::FabricPreset p = make_preset("F" + std::to_string(i), 0.1, std::string(2000, 'c'));
                l.add(p);
            }
        } // closing checkpoints the WAL into the main file
        const auto size = std::filesystem::file_size(trunc);
        QVERIFY(size > 8192);
        std::filesystem::resize_file(trunc, size / 2);
        QCOMPARE(expect_file_error(trunc, [&] {
                     FabricLibrary l(trunc);
                     l.list();
                     l.count();
                 }),
                 QString());
    }

    /// Names are normalised once, where they enter the library, and looked up
    /// the same way: a trailing no-break space or a decomposed accent no longer
    /// makes a second "silk"; the limit counts characters, not bytes.
    void namesAreNormalised()
    {
        FabricLibrary lib(tmp("names.sqlite"));
        lib.add(make_preset("silk", 0.06, "silk"));
        QString e;
        try {
            lib.add(make_preset("silk\u00a0", 0.06, "silk"));
        } catch (const ParameterError& ex) {
            e = ex.what();
        }
        QVERIFY2(e.contains("already exists"), qPrintable(e));
        lib.add(make_preset("Cafe\u0301", 0.1, "x"));                          // decomposed é ...
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(make_preset("Caf\u00e9", 0.1, "x"))); // ... is the composed one
        QCOMPARE(lib.get("Caf\u00e9").name, std::string("Caf\u00e9"));        // stored in NFC
        QVERIFY(lib.find("  silk\u00a0"));                                     // looked up normalised
        std::string e150;
        for (int i = 0; i < 150; ++i) e150 += "\u00e9"; // 300 bytes: refused before as "longer than 200 characters"
        lib.add(make_preset(e150, 0.1, "x"));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(make_preset(e150 + std::string(51, 'x'), 0.1, "x")));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(make_preset("bad\xff", 0.1, "x"))); // was a JSON type_error
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.add(make_preset("two\nlines", 0.1, "x")));
        QVERIFY_THROWS_EXCEPTION(ParameterError, lib.rename("silk", "bad\xff"));
        lib.rename("silk\u00a0", "Silk");
        QVERIFY(lib.find("Silk"));
        lib.remove(std::vector<std::string>{" Silk ", "Cafe\u0301"});
        QCOMPARE(lib.count(), 1);
        // A name stored before the rule is still found, updated and renamed by its own spelling.
        const std::string path = tmp("names.sqlite");
        raw_exec(path, "UPDATE fabrics SET name = 'old\u00a0' WHERE name = '" + e150 + "'");
        QVERIFY(lib.find("old\u00a0"));
        lib.update("old\u00a0", make_preset("x", 0.2, "y"));
        QCOMPARE(lib.count(), 1);
        QCOMPARE(lib.get("old").areal_density_kg_m2, 0.2);
    }

    /// A library document whose fields have the wrong type is a named error,
    /// not an internal one (format = 7 was a nlohmann type_error, exit 3).
    void badLibraryDocumentsAreNamed()
    {
        FabricLibrary lib(tmp("docs.sqlite"));
        for (const char* doc : {R"({"format": 7, "fabrics": []})", R"({"format": null})", R"("just text")",
                                R"({"format": "drapekit-fabric-library", "fabrics": {"a": 1}})",
                                R"({"format": "drapekit-fabric-library", "version": "1", "fabrics": []})",
                                R"([{"preset": {"format": "drapekit-fabric", "parameters": {}}, "name": 5}])"}) {
            QString e;
            try {
                lib.import_all(json::parse(doc), "doc.json");
            } catch (const ParameterError& ex) {
                e = ex.what();
            }
            QVERIFY2(e.startsWith("doc.json"), qPrintable(QString(doc) + ": " + e));
        }
        QCOMPARE(lib.count(), 0);
    }

    /// Reading commands open read-only and explain what they find.
    void readOnlyOpensExplain()
    {
        const std::string empty = tmp("empty.sqlite");
        std::ofstream(empty).close();
        QString e;
        try {
            FabricLibrary l(empty, FabricLibrary::Mode::ReadOnly);
        } catch (const FileError& ex) {
            e = ex.what();
        }
        QVERIFY2(e.contains("empty file, not a fabric library yet") && !e.contains("migrating"), qPrintable(e));
        QCOMPARE(std::filesystem::file_size(empty), std::uintmax_t(0)); // a read did not write
        const std::string lib = tmp("ro.sqlite");
        {
            FabricLibrary l(lib);
            l.add(make_preset("silk", 0.06, "silk"));
        }
        FabricLibrary ro(lib, FabricLibrary::Mode::ReadOnly);
        QCOMPARE(ro.count(), 1);
        QVERIFY_THROWS_EXCEPTION(FileError, ro.add(make_preset("x", 0.1, "x")));
    }

    void fullDiskLeavesTheLibraryIntact()
    {
        const std::string path = tmp("full.sqlite");
        {
            FabricLibrary lib(path);
            lib.add(make_preset("Kept", 0.1, "cotton"));
            lib.limit_pages_for_testing(8);
            bool full = false;
            int added = 0;
            for (int i = 0; i < 200 && !full; ++i) {
                try {
                    lib.add(make_preset("Big " + std::to_string(i), 0.1, std::string(3000, 'x')));
                    ++added;
                } catch (const FileError& e) {
                    full = true;
                    QVERIFY2(QString(e.what()).contains("unchanged"), e.what());
                }
            }
            QVERIFY(full);
            // The failed write left no trace; the ones before it are all there.
            QCOMPARE(lib.count(), 1 + added);
        }
        FabricLibrary again(path);
        QVERIFY(again.find("Kept"));
        for (const auto& r : again.list()) QVERIFY(r.name == "Kept" || r.composition.size() == 3000);
    }
};

QTEST_APPLESS_MAIN(TestFabricLibrary)
#include "tst_fabric_library.moc"
