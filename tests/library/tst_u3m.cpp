// U3M export and import (engine/library/u3m.hpp) and the Blender cloth script
// (engine/library/blender.hpp): round trips keep every field of ours, the U3M
// has what the U3M 1.1 schema requires, another tool's U3M reads its weight and
// thickness, and the Blender numbers follow the documented mapping.
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/library/blender.hpp"
#include "engine/library/starter.hpp"
#include "engine/library/u3m.hpp"

#include <QProcess>
#include <QRegularExpression>
#include <QStandardPaths>
#include <QTemporaryDir>
#include <QTest>
#include <QtCore/qfloat16.h> // QCOMPARE on json values considers the qfloat16 overload: complete it

#include <cmath>

using namespace drape;
using nlohmann::json;

namespace {

/// A preset with every optional part filled: provenance, fit, drape reference, unknown fields.
fabric::FabricPreset fittedPreset()
{
    fabric::FabricPreset p = library::find_starter("cotton").value();
    p.name = "DL-A04 (fitted)";
    p.composition = "65 % polyester, 35 % cotton";
    p.notes = "fitted to record DL-A04\nsecond line";
    p.params[cloth::Param::BendWarp] = 1.234567890123e-5;
    p.params[cloth::Param::Friction] = 0.3;
    p.params[cloth::Param::BendSofteningRadius] = 0.004;
    fabric::Provenance prov;
    prov.tool = "drape fit";
    prov.date = "2026-11-28T10:00:00Z";
    prov.grid = 41;
    prov.records = {"DL-A04"};
    prov.details = {{"model", "softening"}};
    p.provenance = prov;
    fabric::FitSummary fit;
    fit.chi2 = 12.5;
    fit.dof = 10;
    fit.reduced_chi2 = 1.25;
    fit.sample_diameter_m = 0.3;
    fit.disc_diameter_m = 0.15;
    p.fit = fit;
    fabric::DrapeReference d;
    d.percent = 61.25;
    d.sample_diameter_m = 0.3;
    d.disc_diameter_m = 0.15;
    d.method = "drape simulate --grid 60";
    p.drape = d;
    p.extra = {{"supplier", {{"name", "Weaver & Co"}, {"article", 4711}}}};
    return p;
}

} // namespace

class TstU3m : public QObject {
    Q_OBJECT

private slots:
    void exportHasTheSchemasRequiredFields()
    {
        const fabric::FabricPreset p = fittedPreset();
        const json u = library::preset_to_u3m(p, {"2026-11-01T08:00:00Z", "2026-11-02T09:00:00Z"});
        QCOMPARE(QString::fromStdString(u["schema"].get<std::string>()), QStringLiteral("1.1"));
        for (const char* k : {"schema", "material", "custom"}) QVERIFY2(u.contains(k), k);
        const json& m = u["material"];
        for (const char* k : {"name", "id", "created", "modified", "front", "back", "side", "physics", "metadata", "description"})
            QVERIFY2(m.contains(k), k);
        // UUID4, variant 1 (the schema's pattern), stable for a name.
        const QString id = QString::fromStdString(m["id"].get<std::string>());
        QVERIFY2(QRegularExpression("^[0-9a-f]{8}-[0-9a-f]{4}-4[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}$").match(id).hasMatch(),
                 qPrintable(id));
        QCOMPARE(library::preset_to_u3m(p)["material"]["id"], m["id"]);
        QVERIFY(library::preset_to_u3m(library::find_starter("silk").value())["material"]["id"] != m["id"]);
        QCOMPARE(QString::fromStdString(m["created"].get<std::string>()), QStringLiteral("2026-11-01T08:00:00Z"));
        // Physics in the format's units: weight g/m^2, thickness mm.
        const json& ph = m["physics"];
        for (const char* k : {"thickness", "weight", "composition", "devices", "material_type", "construction"}) QVERIFY2(ph.contains(k), k);
        QCOMPARE(ph["weight"].get<double>(), p.params[cloth::Param::AreaDensity] * 1e3);
        QCOMPARE(ph["thickness"].get<double>(), p.params[cloth::Param::Thickness] * 1e3);
        QCOMPARE(QString::fromStdString(ph["devices"]["fab"].get<std::string>()), QStringLiteral("null"));
        const json& parts = ph["composition"]["parts"];
        QCOMPARE(int(parts.size()), 2);
        QCOMPARE(QString::fromStdString(parts[0]["type"].get<std::string>()), QStringLiteral("Polyester"));
        QCOMPARE(parts[0]["ratio"].get<double>(), 0.65);
        QVERIFY(parts[0]["name"].is_null());
        // Our parameters per direction with units, in our vendor block.
        const json& par = u["custom"]["drapekit"]["parameters"];
        QCOMPARE(par["stretch_warp_N_m"]["unit"].get<std::string>(), std::string("N/m"));
        QCOMPARE(par["bend_weft_Nm"]["unit"].get<std::string>(), std::string("N*m"));
        QCOMPARE(par["shear_N_m"]["value"].get<double>(), p.params[cloth::Param::Shear]);
        QCOMPARE(par["bend_warp_Nm"]["value"].get<double>(), 1.234567890123e-5);
        QVERIFY(!par["bend_warp_Nm"]["doc"].get<std::string>().empty());
    }

    void roundTripIsLosslessForOurFields()
    {
        std::vector<fabric::FabricPreset> presets;
        for (const auto& s : library::starters()) presets.push_back(s.preset);
        presets.push_back(fittedPreset());
        presets.push_back(fabric::builtin_fabric("seed-table1").value()); // grid constants too
        QTemporaryDir dir;
        for (const auto& p : presets) {
            const std::string path = dir.filePath("fabric.u3m").toStdString();
            drape::write_file_atomic(path, library::preset_to_u3m(p).dump(2));
            const json back = drape::read_json_file(path);
            QVERIFY(library::is_u3m(back));
            std::string note;
            const fabric::FabricPreset q = library::preset_from_u3m(back, path, &note);
            QCOMPARE(QString::fromStdString(fabric::fabric_to_json(q).dump()), QString::fromStdString(fabric::fabric_to_json(p).dump()));
            QVERIFY2(note.find("preset block") != std::string::npos, note.c_str());
        }
    }

    void anotherToolsWeightWinsAndForeignU3mReads()
    {
        const fabric::FabricPreset p = fittedPreset();
        json u = library::preset_to_u3m(p);
        u["material"]["physics"]["weight"] = 180.0; // edited in another tool
        std::string note;
        const fabric::FabricPreset q = library::preset_from_u3m(u, "edited.u3m", &note);
        QCOMPARE(q.params[cloth::Param::AreaDensity], 0.18);
        QCOMPARE(q.params[cloth::Param::BendWarp], p.params[cloth::Param::BendWarp]);
        QVERIFY2(note.find("weight 180") != std::string::npos, note.c_str());

        // Without the preset block: the documented parameters.
        json noPreset = library::preset_to_u3m(p);
        noPreset["custom"]["drapekit"].erase("preset");
        const fabric::FabricPreset r = library::preset_from_u3m(noPreset, "params.u3m");
        for (const auto& s : cloth::param_table()) QCOMPARE(r.params[s.id], p.params[s.id]);
        QCOMPARE(QString::fromStdString(r.name), QString::fromStdString(p.name));

        // A U3M of another tool (Browzwear's vendor block, which we do not read): weight, thickness, name, composition.
        const json foreign = {
            {"schema", "1.1"},
            {"material",
             {{"id", "3f1c1a2e-9b7d-4c1e-8a2b-0c9d8e7f6a5b"}, {"name", "Jersey 180"}, {"description", "single jersey"},
              {"created", "2020-06-01T00:00:00Z"}, {"modified", "2020-06-01T00:00:00Z"}, {"front", nullptr},
              {"back", nullptr}, {"side", nullptr}, {"metadata", nullptr},
              {"physics",
               {{"weight", 180.0}, {"thickness", 0.6}, {"devices", {{"fab", "null"}}}, {"material_type", nullptr},
                {"construction", nullptr},
                {"composition", {{"parts", json::array({{{"ratio", 0.95}, {"type", "Cotton"}, {"name", nullptr}},
                                                         {{"ratio", 0.05}, {"type", "Elastane"}, {"name", nullptr}}})}}}}}}},
            {"custom", {{"browzwear", {{"bend", {{"length", 15.9}, {"width", 24.1}}}}}}}};
        const fabric::FabricPreset f = library::preset_from_u3m(foreign, "jersey.u3m", &note);
        QCOMPARE(QString::fromStdString(f.name), QStringLiteral("Jersey 180"));
        QCOMPARE(f.params[cloth::Param::AreaDensity], 0.18);
        QVERIFY(std::abs(f.params[cloth::Param::Thickness] - 0.6e-3) < 1e-15);
        QCOMPARE(f.params[cloth::Param::Shear], cloth::FabricParams()[cloth::Param::Shear]); // the table's default
        QCOMPARE(QString::fromStdString(f.composition), QStringLiteral("95 % cotton, 5 % elastane"));
        QVERIFY2(note.find("defaults") != std::string::npos, note.c_str());

        // Not U3M, a newer schema, no name, a weight outside the table: errors naming the field.
        const json notU3m = {{"name", "x"}};
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, library::preset_from_u3m(notU3m, "a.json"));
        json newer = foreign;
        newer["schema"] = "2.0";
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, library::preset_from_u3m(newer, "b.u3m"));
        json noName = foreign;
        noName["material"].erase("name");
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, library::preset_from_u3m(noName, "c.u3m"));
        json heavy = foreign;
        heavy["material"]["physics"]["weight"] = 5e6;
        QVERIFY_THROWS_EXCEPTION(drape::ParameterError, library::preset_from_u3m(heavy, "d.u3m"));

        // A value of the wrong type is refused by name, never dropped (issue 55: "sixty"
        // was read as no weight at all); null is "not stated".
        auto error = [](const json& doc) {
            try {
                library::preset_from_u3m(doc, "e.u3m");
            } catch (const drape::ParameterError& e) {
                return std::string(e.what());
            }
            return std::string();
        };
        json words = foreign;
        words["material"]["physics"]["weight"] = "sixty";
        std::string e = error(words);
        QVERIFY2(e.find("e.u3m") != std::string::npos && e.find("material.physics.weight") != std::string::npos &&
                     e.find("sixty") != std::string::npos,
                 e.c_str());
        json thick = foreign;
        thick["material"]["physics"]["thickness"] = json::array({0.6});
        e = error(thick);
        QVERIFY2(e.find("material.physics.thickness") != std::string::npos, e.c_str());
        json ratio = foreign;
        ratio["material"]["physics"]["composition"]["parts"][1]["ratio"] = "5 %";
        e = error(ratio);
        QVERIFY2(e.find("material.physics.composition.parts[1].ratio") != std::string::npos, e.c_str());
        json physics = foreign;
        physics["material"]["physics"] = "heavy";
        e = error(physics);
        QVERIFY2(e.find("material.physics") != std::string::npos && e.find("heavy") != std::string::npos, e.c_str());
        json unstated = foreign;
        unstated["material"]["physics"]["weight"] = nullptr;
        QCOMPARE(library::preset_from_u3m(unstated, "f.u3m").params[cloth::Param::AreaDensity],
                 cloth::FabricParams()[cloth::Param::AreaDensity]);
    }

    void compositionParts()
    {
        QCOMPARE(library::composition_parts("100 % cotton (3/1 twill, denim)")["parts"][0]["type"].get<std::string>(),
                 std::string("Cotton"));
        const json other = library::composition_parts("70 % merino, 30 % silk");
        QCOMPARE(other["parts"][0]["type"].get<std::string>(), std::string("other"));
        QCOMPARE(other["parts"][0]["name"].get<std::string>(), std::string("merino"));
        QVERIFY(library::composition_parts("cotton blend").is_null());
        QVERIFY(library::composition_parts("50 % cotton").is_null()); // not 100 %
    }

    void blenderSettingsFollowTheDocumentedMapping()
    {
        const fabric::FabricPreset p = library::find_starter("wool").value();
        const double h = 0.01;
        const library::BlenderCloth b = library::blender_cloth(p, h);
        using cloth::Param;
        const auto& v = p.params;
        QCOMPARE(b.vertex_mass_kg, v[Param::AreaDensity] * h * h);
        QCOMPARE(b.tension, 0.001 * 0.5 * (v[Param::StretchWarp] + v[Param::StretchWeft]) * h);
        QCOMPARE(b.compression, b.tension);
        QCOMPARE(b.shear, 0.001 * v[Param::Shear] * h);
        QVERIFY(std::abs(b.bending - 0.01 * 0.5 * (v[Param::BendWarp] + v[Param::BendWeft]) / (h * h)) < 1e-12 * b.bending);
        // Halving the edge: Blender's spring constants are per edge length, its mass per vertex.
        const library::BlenderCloth c = library::blender_cloth(p, h / 2);
        QVERIFY(std::abs(c.tension / b.tension - 0.5) < 1e-12);
        QVERIFY(std::abs(c.bending / b.bending - 4.0) < 1e-9);
        QVERIFY(std::abs(c.vertex_mass_kg / b.vertex_mass_kg - 0.25) < 1e-12);

        const std::string script = library::preset_to_blender_script(p);
        QVERIFY(script.find("s.bending_model = 'ANGULAR'") != std::string::npos);
        QVERIFY(script.find("\"bend_warp_Nm\": ") != std::string::npos);
        // Valid Python (parsed, not run: Blender is not needed for that).
        const QString python = QStandardPaths::findExecutable("python3");
        if (python.isEmpty()) QSKIP("no python3 to parse the script");
        QTemporaryDir dir;
        const QString path = dir.filePath("fabric.py");
        drape::write_file_atomic(path.toStdString(), script);
        QProcess py;
        py.start(python, {"-c", "import ast, sys; ast.parse(open(sys.argv[1]).read())", path});
        QVERIFY(py.waitForFinished(30000));
        QVERIFY2(py.exitCode() == 0, py.readAllStandardError().constData());
    }
};

QTEST_APPLESS_MAIN(TstU3m)
#include "tst_u3m.moc"
