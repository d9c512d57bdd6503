// Preset files: exact round trips (continuum and the seed's 19 parameters),
// typed descriptions, presets written before the typed format, clear errors
// on bad files, atomic writes.
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/fabric/preset.hpp"

#include <QTemporaryDir>
#include <QTest>

#include <fstream>

#include <unistd.h>

using namespace drape::cloth;
using namespace drape::fabric;
using drape::read_file;
using nlohmann::json;

namespace {
std::string write(const QTemporaryDir& d, const char* name, const std::string& text)
{
    const std::string p = d.filePath(name).toStdString();
    std::ofstream(p) << text;
    return p;
}

template <class E>
QString error_of(const std::string& path)
{
    try {
        load_fabric(path);
    } catch (const E& e) {
        return QString::fromStdString(e.what());
    }
    return {};
}
} // namespace

class TestPreset : public QObject {
    Q_OBJECT
private slots:
    void seed_table1_is_the_papers_table()
    {
        const SeedParams s = SeedParams::table1();
        QCOMPARE(s.w, 30.0);
        QCOMPARE(s.u, 30);
        QCOMPARE(s.x0, -15.0);
        QCOMPARE(s.y0, 15.0);
        QCOMPARE(s.cloth_over_mass, 0.5);
        QCOMPARE(s.sst_ku, 150.0);
        QCOMPARE(s.ssh_k, 40.0);
        QCOMPARE(s.sfl_kv, 24.0);
        QCOMPARE(s.sst_dv, 7.0);
        QCOMPARE(s.ssh_d, 6.0);
        QCOMPARE(s.sfl_du, 8.0);
        const FabricPreset p = load_fabric("seed-table1");
        QVERIFY(p.is_seed());
        QVERIFY(p.material().grid_springs.has_value());
        QCOMPARE(p.material().grid_springs->k_shear, 40.0);
    }

    void seed_format_round_trips_exactly()
    {
        SeedParams s;
        s.w = 31.7;
        s.u = 41;
        s.v = 41;
        s.h = 31.7;
        s.cloth_over_mass = 0.123456789012345;
        s.sfl_ku = 1.0 / 3.0;
        s.ssh_d = 6.000000000000001;
        const json j = seed_to_json(s);
        const SeedParams r = seed_from_json(json::parse(j.dump()), "mem");
        QCOMPARE(seed_to_json(r).dump(), j.dump());
        QCOMPARE(r.cloth_over_mass, s.cloth_over_mass);
        QCOMPARE(r.sfl_ku, s.sfl_ku);
        QTemporaryDir d;
        const std::string path = d.filePath("seed.json").toStdString();
        FabricPreset p;
        p.seed = s;
        p.params = continuum_from_seed(s);
        p.extra["note"] = "kept";
        save_fabric(p, path);
        const FabricPreset back = load_fabric(path);
        QVERIFY(back.is_seed());
        QCOMPARE(seed_to_json(*back.seed).dump(), j.dump());
        QCOMPARE(back.extra["note"].get<std::string>(), std::string("kept"));
    }

    void continuum_preset_round_trips()
    {
        FabricParams f;
        f[Param::BendWarp] = 1.234567890123e-5;
        f[Param::Shear] = 17.25;
        f[Param::BendStiffeningRadius] = 0.0125;
        FabricPreset p;
        p.name = "wool worsted";
        p.params = f;
        p.model.edge_contact = false;
        p.model.bending_correction = true;
        p.model.arc_membrane = true;
        p.provenance = Provenance{};
        p.provenance->records = {"DL-A01"};
        p.provenance->grid = 41;
        p.provenance->laying_load = 0.4;
        p.provenance->perturbation_m = 0.006;
        QTemporaryDir d;
        const std::string path = d.filePath("f.json").toStdString();
        save_fabric(p, path);
        const FabricPreset back = load_fabric(path);
        const auto& g = back.params;
        for (int i = 0; i < kParamCount; ++i) QCOMPARE(g.values[static_cast<std::size_t>(i)], f.values[static_cast<std::size_t>(i)]);
        QCOMPARE(back.name, p.name);
        QCOMPARE(back.model.edge_contact, false);
        QCOMPARE(back.model.bending_correction, true);
        QCOMPARE(back.model.arc_membrane, true);
        QVERIFY(back.provenance.has_value());
        QCOMPARE(back.provenance->records.at(0), std::string("DL-A01"));
        QCOMPARE(back.provenance->grid, 41);
        QCOMPARE(back.provenance->laying_load, 0.4);
        QCOMPARE(back.laying(), 0.4); // laid as its records' lab laid them
        FabricPreset starter;
        QCOMPARE(starter.laying(), 1.0); // no provenance: at once
        QCOMPARE(back.perturbation(), 0.006); // as wavy as its lab laid them
        QCOMPARE(starter.perturbation(), drape::cloth::kStartLift); // not stated: the engine's default
        QCOMPARE(back.laid({}).perturbation, 0.006);
        QCOMPARE(back.laid({}).laying_load, 0.4);
        // The file carries the unit-suffixed keys.
        const json j = json::parse(read_file(path));
        QVERIFY(j["parameters"].contains("bend_warp_Nm"));
        QVERIFY(!j["parameters"].contains("bend_warp_N_m"));
    }

    void continuum_seed_conversion_inverts_the_mapping()
    {
        // continuum_from_seed is the inverse of make_model's mapping on the seed's grid:
        // building the model from it gives the seed's spring constants back.
        const SeedParams s = SeedParams::table1();
        FabricParams p = continuum_from_seed(s);
        const ClothMesh m = make_rectangle(s.w * 0.01, s.h * 0.01, s.u + 1, s.v + 1);
        // Areal density of the seed exceeds nothing here, but the model needs valid values elsewhere.
        const ClothModel model = make_model(m, p);
        for (const auto& sp : model.springs) {
            if (sp.kind == SpringKind::StretchU) QVERIFY(std::abs(sp.k - s.sst_ku) < 1e-9 * s.sst_ku);
            if (sp.kind == SpringKind::Shear) QVERIFY(std::abs(sp.k - s.ssh_k) < 1e-9 * s.ssh_k);
        }
        const int interior = m.grid.at(5, 5);
        QVERIFY(std::abs(model.mass(interior) - s.particle_mass_kg()) < 1e-12);
    }

    void presets_written_before_the_typed_format_still_load()
    {
        // Keys before the unit-suffix rule, D as a fraction, a fit without a
        // reduced chi-square: read as today's preset.
        QTemporaryDir d;
        const std::string path = write(d, "old.json", R"({"format":"drapekit-fabric","version":1,"name":"old fit",
            "parameters":{"bend_warp_N_m":2e-6,"bend_weft_N_m":3e-6,"damp_bend_N_m_s":2e-7,"damp_stretch_N_s_m":0.1},
            "drape_coefficient":{"value":0.317,"kind":"simulated","simulated_on":"2026-11-22"},
            "provenance":{"tool":"drape fit","date_utc":"2026-11-22T10:00:00Z","grid":25,"records":[{"id":"DL-A04","source":"x"}]},
            "fit":{"chi2":40.0,"dof":50,"records":[{"sample_diameter_m":0.3,"disc_diameter_m":0.15}]},
            "residual":{"exceeds_noise":false}})");
        const FabricPreset p = load_fabric(path);
        QCOMPARE(p.name, std::string("old fit"));
        QCOMPARE(p.params[Param::BendWarp], 2e-6);
        QCOMPARE(p.params[Param::BendWeft], 3e-6);
        QCOMPARE(p.params[Param::DampBend], 2e-7);
        QCOMPARE(p.params[Param::DampStretch], 0.1);
        QVERIFY(p.drape.has_value());
        QVERIFY(std::abs(p.drape->percent - 31.7) < 1e-9);
        QCOMPARE(p.drape->date, std::string("2026-11-22"));
        QVERIFY(p.provenance && p.provenance->grid == 25 && p.provenance->tool == "drape fit");
        QCOMPARE(p.provenance->records.at(0), std::string("DL-A04"));
        QVERIFY(p.fit && p.fit->reduced_chi2 && std::abs(*p.fit->reduced_chi2 - 0.8) < 1e-12);
        QCOMPARE(p.fit->sample_diameter_m, 0.3);
        QVERIFY(p.extra.contains("residual"));
        // Written back in today's format: percent, unit-suffixed keys; nothing lost.
        const json j = fabric_to_json(p);
        QCOMPARE(j["drape_coefficient"]["percent"].get<double>(), p.drape->percent);
        QVERIFY(!j["drape_coefficient"].contains("value"));
        QVERIFY(j["parameters"].contains("damp_bend_Nms"));
        QCOMPARE(j["fit"]["records"][0]["sample_diameter_m"].get<double>(), 0.3);
        QCOMPARE(j["residual"]["exceeds_noise"].get<bool>(), false);
        const FabricPreset again = fabric_from_json(j, "again");
        QCOMPARE(fabric_to_json(again).dump(), j.dump());
    }

    void bad_files_give_clear_errors()
    {
        QTemporaryDir d;
        QVERIFY(error_of<drape::FileError>("/nonexistent/f.json").contains("/nonexistent/f.json"));
        QVERIFY(error_of<drape::FileError>(write(d, "bad.json", "{ \"format\": ")).contains("not valid JSON"));
        QVERIFY(error_of<drape::FileError>(write(d, "deep.json", std::string(5000, '[') + std::string(5000, ']'))).contains("nested deeper"));
        QVERIFY(error_of<drape::FileError>(write(d, "inf.json", R"({"format":"drapekit-fabric","parameters":{"shear_N_m":1e400}})")).contains("inf.json"));
        QString e = error_of<drape::ParameterError>(write(d, "s.json", R"({"format":"drapekit-fabric","version":1,"parameters":{"shear_N_m":"stiff"}})"));
        QVERIFY2(e.contains("s.json") && e.contains("parameters.shear_N_m") && e.contains("stiff"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "r.json", R"({"format":"drapekit-fabric","parameters":{"bend_warp_N_m":-1}})"));
        QVERIFY2(e.contains("bend_warp_N_m") && e.contains("-1") && e.contains("outside"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "u.json", R"({"format":"drapekit-fabric","parameters":{"bend_wrap_N_m":1e-5}})"));
        QVERIFY2(e.contains("bend_wrap_N_m"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "m.json", R"({"format":"drapekit-fabric","parameters":{},"model":{"edge_contact":"yes"}})"));
        QVERIFY2(e.contains("m.json") && e.contains("model.edge_contact") && e.contains("yes"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "m.json", R"({"format":"drapekit-fabric","parameters":{},"model":{"bending_correction":1}})"));
        QVERIFY2(e.contains("m.json") && e.contains("model.bending_correction") && e.contains("1"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "m.json", R"({"format":"drapekit-fabric","parameters":{},"model":{"arc_membrane":"on"}})"));
        QVERIFY2(e.contains("m.json") && e.contains("model.arc_membrane") && e.contains("on"), qPrintable(e));
        // A preset written before the key existed drapes with the plain stencils it was made with.
        QCOMPARE(load_fabric(write(d, "old.json", R"({"format":"drapekit-fabric","parameters":{},"model":{"edge_contact":true}})"))
                     .model.bending_correction,
                 false);
        // ... and with chords.
        QCOMPARE(load_fabric(write(d, "old2.json", R"({"format":"drapekit-fabric","parameters":{},"model":{"edge_contact":true}})")).model.arc_membrane,
                 false);
        e = error_of<drape::ParameterError>(write(d, "n.json", R"({"format":"drapekit-fabric","parameters":{"bend_stiffening_radius_m":0.2}})"));
        QVERIFY2(e.contains("bend_stiffening_radius_m") && e.contains("outside"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "f.json", R"({"format":"other"})"));
        QVERIFY2(e.contains("format"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "seed.json", R"({"format":"seed-19","w":30,"h":30,"u":30,"v":30,"x0":0,"y0":0,"z0":0,"ClothOverMass":0,"SstKu":1,"SstDu":1,"SstKv":1,"SstDv":1,"SshK":1,"SshD":1,"SflKu":1,"SflDu":1,"SflKv":1,"SflDv":1})"));
        QVERIFY2(e.contains("ClothOverMass"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "seed2.json", R"({"format":"seed-19","w":30})"));
        QVERIFY2(e.contains("missing") && e.contains("'h'"), qPrintable(e));
        // A seed preset whose continuum equivalent is no fabric (1e302 g/m^2) is refused.
        e = error_of<drape::ParameterError>(write(d, "seed3.json", R"({"format":"seed-19","w":30,"h":30,"u":30,"v":30,"x0":0,"y0":0,"z0":0,"ClothOverMass":1e-300,"SstKu":1,"SstDu":1,"SstKv":1,"SstDv":1,"SshK":1,"SshD":1,"SflKu":1,"SflDu":1,"SflKv":1,"SflDv":1})"));
        QVERIFY2(e.contains("areal_density_kg_m2") && e.contains("outside"), qPrintable(e));
        e = error_of<drape::FileError>(write(d, "d.json", R"({"format":"drapekit-fabric","parameters":{},"drape_coefficient":{"percent":150}})"));
        QVERIFY2(e.contains("drape_coefficient.percent") && e.contains("150"), qPrintable(e));
    }

    /// Every seed-19 field has a range, and a continuum value out of the table
    /// names the seed fields that make it (library add stored SflKu = 1e300,
    /// and named only the continuum key for ClothOverMass = 1e-300).
    void seed_fields_are_bounded()
    {
        const json ok = seed_to_json(SeedParams::table1());
        QCOMPARE(seed_from_json(ok, "ok").sst_ku, 150.0);
        struct Case {
            const char* key;
            double value;
        };
        for (const auto& c : std::vector<Case>{{"SflKu", 1e300}, {"SflDv", 1e6}, {"SshK", -1}, {"w", 1e9}, {"x0", 1e300}, {"u", 2000}}) {
            json j = ok;
            j[c.key] = c.value;
            QString e;
            try {
                seed_from_json(j, "s.json");
            } catch (const drape::ParameterError& ex) {
                e = ex.what();
            }
            QVERIFY2(e.contains(QString("s.json: field '") + c.key + "'"), qPrintable(QString(c.key) + ": " + e));
        }
        json heavy = ok;
        heavy["ClothOverMass"] = 1e-300;
        QString e;
        try {
            seed_from_json(heavy, "s.json");
        } catch (const drape::ParameterError& ex) {
            e = ex.what();
        }
        QVERIFY2(e.contains("'ClothOverMass'") && e.contains("areal_density_kg_m2") && e.contains("1e-300"), qPrintable(e));
    }

    /// The fitted set-up a preset carries is range-checked (predict scales its grid by it).
    void fit_setup_is_bounded()
    {
        json j = json::parse(R"({"format":"drapekit-fabric","version":1,"parameters":{},
                                 "fit":{"chi2":1,"dof":1,"records":[{"sample_diameter_m":1e300}]}})");
        QString e;
        try {
            fabric_from_json(j, "p.json");
        } catch (const drape::Error& ex) {
            e = ex.what();
        }
        QVERIFY2(e.contains("fit.records[0].sample_diameter_m") && e.contains("outside"), qPrintable(e));
        const auto load_error = [](const json& preset) {
            try {
                fabric_from_json(preset, "p.json");
            } catch (const drape::Error& ex) {
                return QString(ex.what());
            }
            return QString();
        };
        // A set-up value of another type is refused, not "unknown" (issue 55: a string
        // "0.15" was ignored and predict draped at grid 41 instead of 83).
        for (const char* key : {"sample_diameter_m", "disc_diameter_m"})
            for (const json& bad : {json("0.15"), json(nullptr), json::array({0.15})}) {
                json k = j;
                k["fit"]["records"][0] = {{"sample_diameter_m", 0.3}, {"disc_diameter_m", 0.15}};
                k["fit"]["records"][0][key] = bad;
                e = load_error(k);
                QVERIFY2(e.contains(QString("fit.records[0].") + key) && e.contains("p.json") && e.contains("must be a number"),
                         qPrintable(e));
            }
        {
            json k = j;
            k["fit"]["records"] = "DL-A04";
            e = load_error(k);
            QVERIFY2(e.contains("fit.records") && e.contains("array"), qPrintable(e));
        }
        // The provenance's grid is an integer, a string is refused too.
        for (const json& bad : {json("83"), json(41.5), json(nullptr)}) {
            json k = j;
            k["provenance"] = {{"tool", "drape fit"}, {"grid", bad}};
            e = load_error(k);
            QVERIFY2(e.contains("provenance.grid") && e.contains("p.json"), qPrintable(e));
        }
        j["fit"]["records"][0]["sample_diameter_m"] = 0.3;
        QCOMPARE(fabric_from_json(j, "p.json").fit->sample_diameter_m, 0.3);
        // The lab's laying in the provenance: a fraction of gravity in (0, 1].
        for (const json& bad : {json(0.0), json(1.5), json("0.4")}) {
            j["provenance"] = {{"tool", "drape fit"}, {"laying_load", bad}};
            e = load_error(j);
            QVERIFY2(e.contains("provenance.laying_load") && e.contains("p.json"), qPrintable(e));
        }
        j["provenance"]["laying_load"] = 0.4;
        QCOMPARE(fabric_from_json(j, "p.json").laying(), 0.4);
        // The lab's waviness: a length in [0, 0.05] m.
        for (const json& bad : {json(-0.001), json(0.2), json("6mm")}) {
            j["provenance"]["perturbation_m"] = bad;
            e = load_error(j);
            QVERIFY2(e.contains("provenance.perturbation_m") && e.contains("p.json"), qPrintable(e));
        }
        j["provenance"]["perturbation_m"] = 0.0;
        QCOMPARE(fabric_from_json(j, "p.json").perturbation(), 0.0);
        j["provenance"].erase("perturbation_m");
        QCOMPARE(fabric_from_json(j, "p.json").perturbation(), drape::cloth::kStartLift);
    }

    void failed_save_keeps_the_old_file()
    {
        QTemporaryDir d;
        const std::string path = d.filePath("keep.json").toStdString();
        FabricPreset p;
        save_fabric(p, path);
        const std::string before = read_file(path);
        // A folder with the temporary file's name makes the write fail.
        QDir().mkpath(QString::fromStdString(path + ".tmp-" + std::to_string(::getpid())));
        QVERIFY_THROWS_EXCEPTION(drape::FileError, save_fabric(p, path));
        QCOMPARE(read_file(path), before);
    }
};

QTEST_APPLESS_MAIN(TestPreset)
#include "tst_preset.moc"
