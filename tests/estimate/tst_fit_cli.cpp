// `drape fit` on the command line: the output locations are checked before the
// fit runs (a fit takes minutes; it must not fail to save at the end).
#include <QDir>
#include <QProcess>
#include <QTemporaryDir>
#include <QtTest>

class TestFitCli : public QObject {
    Q_OBJECT

    struct Run {
        int code = -1;
        QString err;
    };
    static Run drape(const QStringList& args)
    {
        QProcess p;
        p.start(QCoreApplication::applicationDirPath() + "/../bin/drape", args);
        Run r;
        if (!p.waitForFinished(60000)) {
            p.kill();
            return r;
        }
        r.code = p.exitCode();
        r.err = QString::fromUtf8(p.readAllStandardError());
        return r;
    }

private slots:
    void unwritableOutputFailsBeforeFitting()
    {
        const QString record = DRAPE_SOURCE_DIR "/examples/DL-A04";
        QElapsedTimer t;
        t.start();
        const Run r = drape({"fit", record, "--out", "/proc/drapekit-no-such-folder/fabric.json", "--quiet"});
        QCOMPARE(r.code, 1);
        QVERIFY2(r.err.contains("--out /proc/drapekit-no-such-folder/fabric.json") && r.err.contains("cannot create the folder"), qPrintable(r.err));
        QVERIFY2(t.elapsed() < 30000, "the check must come before the fit (which takes minutes)");
        const Run rep = drape({"fit", record, "--out", QDir::tempPath() + "/drapekit-cli-test.json", "--report", "/proc/drapekit-no-such-report", "--quiet"});
        QCOMPARE(rep.code, 1);
        QVERIFY2(rep.err.contains("--report /proc/drapekit-no-such-report"), qPrintable(rep.err));
    }

    void missingOutputFolderIsCreated()
    {
        QTemporaryDir tmp;
        QVERIFY(tmp.isValid());
        const QString out = tmp.path() + "/new/sub/fabric.json";
        // A record that does not exist: the run fails after the output check, quickly.
        const Run r = drape({"fit", tmp.path() + "/no-such-record", "--out", out, "--quiet"});
        QVERIFY(r.code != 0);
        QVERIFY2(r.err.contains("no-such-record"), qPrintable(r.err));
        QVERIFY(QDir(tmp.path() + "/new/sub").exists());
        QVERIFY(QDir(tmp.path() + "/new/sub").entryList(QDir::Files | QDir::Hidden).isEmpty()); // no probe file left behind
    }

    void badBranchAndGridOptionsAreRefusedByName()
    {
        const QString record = DRAPE_SOURCE_DIR "/examples/DL-A04";
        const QString out = QDir::tempPath() + "/drapekit-cli-test.json";
        const Run branch = drape({"fit", record, "--out", out, "--branch", "sideways", "--quiet"});
        QCOMPARE(branch.code, 2); // a usage error
        QVERIFY2(branch.err.contains("--branch") && branch.err.contains("'sideways'") && branch.err.contains("measured, random"),
                 qPrintable(branch.err));
        const Run refine = drape({"fit", record, "--out", out, "--refine-grid", "21", "--quiet"});
        QVERIFY(refine.code != 0);
        QVERIFY2(refine.err.contains("--refine-grid 21") && refine.err.contains("--grid 25"), qPrintable(refine.err));
        const Run folds = drape({"simulate", "--fabric", "seed-table1", "--folds", "1", "--quiet"});
        QVERIFY(folds.code != 0);
        QVERIFY2(folds.err.contains("--folds") && folds.err.contains("1 is outside [2, 16]"), qPrintable(folds.err));
        const Run cmp = drape({"compare", record, "--fabric", DRAPE_SOURCE_DIR "/docs/fit-report/DL-A08.fabric.json", "--branch", "x", "--quiet"});
        QCOMPARE(cmp.code, 2);
        QVERIFY2(cmp.err.contains("--branch: 'x'"), qPrintable(cmp.err));
    }
};

QTEST_GUILESS_MAIN(TestFitCli)
#include "tst_fit_cli.moc"
