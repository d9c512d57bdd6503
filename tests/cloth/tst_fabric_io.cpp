// Preset files: exact round trips (continuum and the seed's 19 parameters),
// clear errors on bad files, atomic writes.
#include "engine/cloth/error.hpp"
#include "engine/cloth/fabric_io.hpp"

#include <QTemporaryDir>
#include <QtTest>

#include <fstream>

#include <unistd.h>

using namespace drape::cloth;
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

class TestFabricIo : public QObject {
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
        QVERIFY(std::holds_alternative<SeedParams>(p.fabric));
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
        p.fabric = s;
        p.extra["note"] = "kept";
        save_fabric(p, path);
        const FabricPreset back = load_fabric(path);
        QCOMPARE(seed_to_json(std::get<SeedParams>(back.fabric)).dump(), j.dump());
        QCOMPARE(back.extra["note"].get<std::string>(), std::string("kept"));
    }

    void continuum_preset_round_trips()
    {
        FabricParams f;
        f.name = "wool worsted";
        f[Param::BendWarp] = 1.234567890123e-5;
        f[Param::Shear] = 17.25;
        f[Param::BendStiffeningRadius] = 0.0125;
        FabricPreset p;
        p.fabric = f;
        p.model.edge_contact = false;
        p.extra["provenance"] = {{"records", {"DL-A01"}}};
        QTemporaryDir d;
        const std::string path = d.filePath("f.json").toStdString();
        save_fabric(p, path);
        const FabricPreset back = load_fabric(path);
        const auto& g = std::get<FabricParams>(back.fabric);
        for (int i = 0; i < kParamCount; ++i) QCOMPARE(g.values[static_cast<std::size_t>(i)], f.values[static_cast<std::size_t>(i)]);
        QCOMPARE(g.name, f.name);
        QCOMPARE(back.model.edge_contact, false);
        QCOMPARE(back.extra["provenance"]["records"][0].get<std::string>(), std::string("DL-A01"));
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

    void bad_files_give_clear_errors()
    {
        QTemporaryDir d;
        QVERIFY(error_of<drape::FileError>("/nonexistent/f.json").contains("/nonexistent/f.json"));
        QVERIFY(error_of<drape::FileError>(write(d, "bad.json", "{ \"format\": ")).contains("not valid JSON"));
        QString e = error_of<drape::ParameterError>(write(d, "s.json", R"({"format":"drapekit-fabric","version":1,"parameters":{"shear_N_m":"stiff"}})"));
        QVERIFY2(e.contains("s.json") && e.contains("parameters.shear_N_m") && e.contains("stiff"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "r.json", R"({"format":"drapekit-fabric","parameters":{"bend_warp_N_m":-1}})"));
        QVERIFY2(e.contains("bend_warp_N_m") && e.contains("-1") && e.contains("outside"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "u.json", R"({"format":"drapekit-fabric","parameters":{"bend_wrap_N_m":1e-5}})"));
        QVERIFY2(e.contains("bend_wrap_N_m"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "m.json", R"({"format":"drapekit-fabric","parameters":{},"model":{"edge_contact":"yes"}})"));
        QVERIFY2(e.contains("m.json") && e.contains("model.edge_contact") && e.contains("yes"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "n.json", R"({"format":"drapekit-fabric","parameters":{"bend_stiffening_radius_m":0.2}})"));
        QVERIFY2(e.contains("bend_stiffening_radius_m") && e.contains("outside"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "f.json", R"({"format":"other"})"));
        QVERIFY2(e.contains("format"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "seed.json", R"({"format":"seed-19","w":30,"h":30,"u":30,"v":30,"x0":0,"y0":0,"z0":0,"ClothOverMass":0,"SstKu":1,"SstDu":1,"SstKv":1,"SstDv":1,"SshK":1,"SshD":1,"SflKu":1,"SflDu":1,"SflKv":1,"SflDv":1})"));
        QVERIFY2(e.contains("ClothOverMass"), qPrintable(e));
        e = error_of<drape::ParameterError>(write(d, "seed2.json", R"({"format":"seed-19","w":30})"));
        QVERIFY2(e.contains("missing") && e.contains("'h'"), qPrintable(e));
    }

    void failed_save_keeps_the_old_file()
    {
        QTemporaryDir d;
        const std::string path = d.filePath("keep.json").toStdString();
        FabricPreset p;
        p.fabric = FabricParams();
        save_fabric(p, path);
        const std::string before = read_file(path);
        // A folder with the temporary file's name makes the write fail.
        QDir().mkpath(QString::fromStdString(path + ".tmp-" + std::to_string(::getpid())));
        QVERIFY_THROWS_EXCEPTION(drape::FileError, save_fabric(p, path));
        QCOMPARE(read_file(path), before);
    }
};

QTEST_APPLESS_MAIN(TestFabricIo)
#include "tst_fabric_io.moc"
