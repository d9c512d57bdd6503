// Issue 14's done-when for a fitted preset, as a user runs it: the bundled
// example record fitted with `drape fit` (its defaults), then the preset draped
// from flat with `drape simulate --grid G --seed K` at G = 41, 61, 81 and K = 1-3.
// A preset is a fabric, not a mesh: D within 1 point and node counts within 1 of
// each other over the grids (the D part not met: an expected failure, below),
// and the mean D within 2 points of the record.
// Measured data (examples/DL-A04, the lab's own D), not the engine's own truth.
#include <QJsonArray>
#include <QJsonDocument>
#include <QJsonObject>
#include <QProcess>
#include <QTemporaryDir>
#include <QTest>

#include <algorithm>
#include <cmath>

class TestCliSlow : public QObject {
    Q_OBJECT

    struct Out {
        int code = -1;
        QByteArray out;
        QString err;
    };
    static Out run(const QStringList& args)
    {
        QProcess p;
        p.start(QCoreApplication::applicationDirPath() + "/../bin/drape", args);
        Out r;
        if (!p.waitForFinished(400000)) { // a fit takes under a minute, a grid-81 drape about 30 s
            r.err = "drape " + args.join(' ') + ": " + (p.state() == QProcess::NotRunning ? p.errorString() : "no result within 400 s");
            p.kill();
            p.waitForFinished();
            return r;
        }
        if (p.exitStatus() != QProcess::NormalExit) r.err = "drape " + args.join(' ') + " crashed: ";
        r.code = p.exitStatus() == QProcess::NormalExit ? p.exitCode() : -1;
        r.out = p.readAllStandardOutput();
        r.err += QString::fromUtf8(p.readAllStandardError());
        return r;
    }

private slots:
    void fittedPresetConvergesUnderRefinement()
    {
        QTemporaryDir tmp;
        QVERIFY(tmp.isValid());
        const QString preset = tmp.filePath("fabric.json");
        const Out fit = run({"fit", DRAPE_SOURCE_DIR "/examples/DL-A04", "--out", preset, "--json", "--quiet"});
        QVERIFY2(fit.code == 0, qPrintable(fit.err));
        const QJsonObject rec = QJsonDocument::fromJson(fit.out).object()["fit"].toObject()["records"].toArray().at(0).toObject();
        const double measured_D = rec["measured_drape_coefficient_percent"].toDouble(NAN);
        const int measured_nodes = static_cast<int>(std::lround(rec["measured_node_count"].toDouble(NAN)));
        QVERIFY2(std::isfinite(measured_D) && measured_nodes > 0, fit.out.constData());
        // Three seeds: from flat the fold count is a bifurcation each seed picks
        // (this preset lays 6, 7 or 8 folds, a fold more about 1.5 points more D),
        // so one seed says little about the preset (docs/results-log.md: the
        // preset of 2026-12-02 before the hem fix passed at seed 1 with a spread of
        // 0.82 and had 1.11 and 1.38 at seeds 2 and 3).
        double sum = 0, spread_max = 0;
        int drapes = 0;
        for (const char* seed : {"1", "2", "3"}) {
            double lo = 1e9, hi = -1e9;
            int nlo = 1000, nhi = -1;
            for (const char* grid : {"41", "61", "81"}) {
                // 3,000 Newton iterations per level: at the lab's waviness this preset's
                // 6-fold drape at grid 81 creeps to rest in 1,900 (D 29.30 % after 1,000,
                // 29.29 % at rest); the default budget of 1,000 stops it (exit 4).
                const Out sim = run({"simulate", "--fabric", preset, "--sample-diameter", "300mm", "--disc-diameter", "150mm", "--grid", grid, "--seed",
                                     seed, "--json", "--max-iterations", "3000"});
                QVERIFY2(sim.code == 0, qPrintable(QString("seed %1 grid %2: exit %3, %4").arg(seed).arg(grid).arg(sim.code).arg(sim.err)));
                const QJsonObject j = QJsonDocument::fromJson(sim.out).object();
                QVERIFY2(j["converged"].toBool(), qPrintable(QString("seed %1 grid %2 not at rest").arg(seed).arg(grid)));
                const double D = j["drape_coefficient_percent"].toDouble(NAN);
                const int nodes = j["node_count"].toInt(-1);
                qInfo("seed %s grid %s: D = %.2f %% (record %.2f %%), %d nodes (record %d), %d Newton iterations", seed, grid, D, measured_D, nodes,
                      measured_nodes, j["newton_iterations"].toInt());
                sum += D;
                ++drapes;
                lo = std::min(lo, D);
                hi = std::max(hi, D);
                nlo = std::min(nlo, nodes);
                nhi = std::max(nhi, nodes);
            }
            qInfo("seed %s: D spread over grids 41-81 %.2f points", seed, hi - lo);
            spread_max = std::max(spread_max, hi - lo);
            // One seed's drape keeps its fold count under refinement.
            QVERIFY2(nhi - nlo <= 1, qPrintable(QString("seed %1: node counts %2..%3 over grids 41-81").arg(seed).arg(nlo).arg(nhi)));
        }
        // It is the record's fabric: the mean over the seeds and grids within 2
        // points of the record.
        const double mean = sum / drapes;
        qInfo("mean D %.2f %% over seeds 1-3 and grids 41-81 (record %.2f %%)", mean, measured_D);
        QVERIFY2(std::abs(mean - measured_D) <= 2.0, qPrintable(QString("mean D %1 % over seeds 1-3 and grids 41-81 against the record's %2 %").arg(mean).arg(measured_D)));
        // Issue 14's convergence: the preset's D within 1 point over grids 41-81, at
        // every seed.
        // Not met for this limp preset: D falls by 1.1-1.4 points from grid 41 to 81
        // at every seed with the fold count unchanged - the rim bend under-resolved
        // on the coarser grids (docs/decisions/0019-drapemeter-mesh.md). An
        // expected failure, so the day it holds the test says so (XPASS fails).
        qInfo("largest D spread over grids 41-81: %.2f points", spread_max);
        QEXPECT_FAIL("", "issue 14's 1-point convergence over grids 41-81 is not met by the bundled preset (1.1-1.4 points per seed): docs/decisions/0019-drapemeter-mesh.md", Continue);
        QVERIFY2(spread_max <= 1.0, qPrintable(QString("D spread up to %1 points over grids 41-81").arg(spread_max)));
    }
};

QTEST_GUILESS_MAIN(TestCliSlow)
#include "tst_cli_slow.moc"
