// Export of a continuum preset to the seed paper's 19 grid constants.
#include "engine/core/error.hpp"
#include "engine/estimate/seed_export.hpp"

#include <QTest>

using namespace drape;
using cloth::Param;

class TestSeedExport : public QObject {
    Q_OBJECT
private slots:
    /// Mass, stretch and shear are exact: the seed -> continuum mapping of the
    /// engine (continuum_from_seed) gives the preset back.
    void exactPartRoundTrips()
    {
        cloth::FabricParams p;
        p[Param::AreaDensity] = 0.23;
        p[Param::Shear] = 35;
        p[Param::StretchWarp] = 1800;
        p[Param::StretchWeft] = 900;
        const fabric::SeedParams s = estimate::seed_without_flexion(p, 0.30, 24);
        QCOMPARE(s.u, 24);
        QCOMPARE(s.w, 30.0);
        const cloth::FabricParams back = fabric::continuum_from_seed(s);
        for (Param q : {Param::AreaDensity, Param::Shear, Param::StretchWarp, Param::StretchWeft})
            QVERIFY2(std::abs(back[q] - p[q]) <= 1e-12 * p[q], qPrintable(QString("%1: %2 vs %3").arg(int(q)).arg(back[q]).arg(p[q])));
    }

    /// The flexion springs are calibrated on the drape coefficient: the seed
    /// constants drape like the preset on the same set-up and grid, with warp :
    /// weft flexion in the ratio of the bending rigidities.
    void flexionMatchesTheDrapeCoefficient()
    {
        cloth::FabricParams p;
        p[Param::BendWarp] = 2e-5;
        p[Param::BendWeft] = 5e-6;
        cloth::DrapeSetup setup;
        setup.grid = 17;
        const estimate::SeedExport e = estimate::export_seed(p, setup);
        qInfo("preset D %.2f, seed D %.2f, SflKu %.3g, SflKv %.3g, %d simulations", e.target_dc_percent, e.seed_dc_percent, e.seed.sfl_ku,
              e.seed.sfl_kv, e.simulations);
        QVERIFY2(e.matched, qPrintable(QString::fromStdString(e.note)));
        QVERIFY(std::abs(e.seed_dc_percent - e.target_dc_percent) <= 0.5);
        QVERIFY(std::abs(e.seed.sfl_ku / e.seed.sfl_kv - 4.0) < 1e-9);
        // The exported constants drape to that D when simulated on their own.
        double d = 0;
        for (std::uint64_t k = 0; k < 2; ++k) {
            cloth::DrapeSetup s = setup;
            s.seed = setup.seed + k;
            d += cloth::simulate_drape(cloth::Material(fabric::continuum_from_seed(e.seed), fabric::grid_springs(e.seed)), s).metrics.drape_coefficient_percent / 2;
        }
        QVERIFY(std::abs(d - e.seed_dc_percent) < 1e-9);
    }

    void stretchBelowShearIsRefused()
    {
        cloth::FabricParams p;
        p[Param::Shear] = 500;
        p[Param::StretchWarp] = 400;
        try {
            estimate::seed_without_flexion(p, 0.30, 24);
            QFAIL("no error");
        } catch (const ParameterError& e) {
            const QString m = e.what();
            QVERIFY2(m.contains("stretch") && m.contains("400") && m.contains("500"), qPrintable(m));
        }
    }
};

QTEST_GUILESS_MAIN(TestSeedExport)
#include "tst_seed_export.moc"
