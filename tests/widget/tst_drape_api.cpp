// The embedding API a garment CAD uses (DrapeView / DrapeController): a fabric
// by its library name, drape to rest with a progress fraction, positions and
// metrics read back in memory - and they are what the command line computes
// for the same input (the drapemeter: `drape simulate`); a garment mesh with a
// pinned vertex drapes on an imported body and ends outside it, at the rest
// state the engine computes headless from the same body, mesh and fabric.
#include "widget/drape_view.hpp"

#include "engine/cloth/colliders.hpp"
#include "engine/cloth/model.hpp"
#include "engine/library/resolve.hpp"
#include "importers/body.hpp"

#include <QFile>
#include <QJsonDocument>
#include <QJsonObject>
#include <QProcess>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QTextStream>
#include <QTest>

#include <cmath>
#include <numbers>

using drape::widget::DrapeController;
using drape::widget::DrapeView;
namespace Drape = drape::widget::Drape;
using namespace drape;

namespace {

cloth::Positions readObjVertices(const QString& path)
{
    QFile f(path);
    if (!f.open(QIODevice::ReadOnly)) return {};
    std::vector<Eigen::Vector3d> v;
    QTextStream in(&f);
    while (!in.atEnd()) {
        const QStringList t = in.readLine().split(' ', Qt::SkipEmptyParts);
        if (t.size() == 4 && t[0] == QLatin1String("v")) v.emplace_back(t[1].toDouble(), t[2].toDouble(), t[3].toDouble());
    }
    cloth::Positions X(Eigen::Index(v.size()), 3);
    for (std::size_t i = 0; i < v.size(); ++i) X.row(Eigen::Index(i)) = v[i].transpose();
    return X;
}

/// A closed, upright cylinder (radius r, height h, standing on z = 0) as an OBJ
/// file: a body a CAD might hand over, with outward winding. OBJ is y up: a
/// world point (x, y, z) is written as (x, z, -y), a rotation, so the winding stays.
void writeCylinderObj(const QString& path, double r, double h, int seg)
{
    QFile f(path);
    QVERIFY(f.open(QIODevice::WriteOnly));
    QTextStream o(&f);
    o.setRealNumberPrecision(12);
    for (int k = 0; k < seg; ++k) {
        const double t = 2 * std::numbers::pi * k / seg;
        o << "v " << r * std::cos(t) << " 0 " << -r * std::sin(t) << '\n';
    }
    for (int k = 0; k < seg; ++k) {
        const double t = 2 * std::numbers::pi * k / seg;
        o << "v " << r * std::cos(t) << ' ' << h << ' ' << -r * std::sin(t) << '\n';
    }
    o << "v 0 0 0\nv 0 " << h << " 0\n";
    const int bottom = 2 * seg + 1, top = 2 * seg + 2; // 1-based
    for (int k = 0; k < seg; ++k) {
        const int a = k + 1, b = (k + 1) % seg + 1, c = seg + k + 1, d = seg + (k + 1) % seg + 1;
        o << "f " << a << ' ' << b << ' ' << d << "\nf " << a << ' ' << d << ' ' << c << '\n'; // side, outward
        o << "f " << top << ' ' << c << ' ' << d << '\n';                                    // top cap, up
        o << "f " << bottom << ' ' << b << ' ' << a << '\n';                                 // bottom cap, down
    }
}

} // namespace

class TstDrapeApi : public QObject {
    Q_OBJECT

private slots:
    void initTestCase()
    {
        QVERIFY(m_tmp.isValid());
        // A library of this test's own: the starter fabrics, as a brand-new user's.
        m_library = m_tmp.filePath("library.sqlite");
        library::FabricLibrary lib = library::open_library(m_library.toStdString(), library::FabricLibrary::Mode::ReadWrite);
        QCOMPARE(library::add_starter_fabrics(lib), 4);
        qputenv("DRAPE_LIBRARY", m_library.toUtf8()); // the command line's default library too
    }

    void drapemeterByLibraryNameMatchesTheCommandLine()
    {
        DrapeView v;
        v.resize(480, 360);
        v.show();
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        v.setLibraryPath(m_library);
        v.setFabricPreset(QStringLiteral("Cotton plain weave (class preset)")); // a library name
        QCOMPARE(errors.count(), 0);
        QCOMPARE(QString::fromStdString(v.controller()->preset().name), QStringLiteral("Cotton plain weave (class preset)"));
        v.setGridSize(25);
        v.setRestResidual(1e-6);
        v.setViewPreset(Drape::Top);
        QSignalSpy progress(&v, &DrapeView::drapeProgress);
        QSignalSpy results(&v, &DrapeView::resultsReady);
        QSignalSpy rest(&v, &DrapeView::restReached);
        v.drapeToRest();
        QTRY_VERIFY_WITH_TIMEOUT(results.count() > 0 || errors.count() > 0, 300000);
        QVERIFY2(errors.isEmpty(), errors.isEmpty() ? "" : qPrintable(errors.first().at(0).toString()));
        QTRY_COMPARE(rest.count(), 1);

        // A real progress fraction: in [0, 1], never going back, ending at 1 with a status line.
        QVERIFY(progress.count() >= 2);
        double last = -1;
        for (const auto& p : progress) {
            const double f = p.at(0).toDouble();
            QVERIFY2(f >= 0 && f <= 1, qPrintable(QString::number(f)));
            QVERIFY(f >= last);
            last = f;
        }
        QCOMPARE(last, 1.0);
        QVERIFY(progress.last().at(1).toString().contains("converged"));
        QVERIFY(!v.controller()->running());

        // Positions and metrics in memory.
        const cloth::Positions x = v.positions();
        const drape::widget::DrapeResultsPtr r = v.lastResults();
        QVERIFY(r && r->drape);
        QCOMPARE(x.rows(), r->x.rows());
        QCOMPARE(v.drapeCoefficient(), r->drape->metrics.drape_coefficient_percent);
        QVERIFY(v.drapeCoefficient() > 30 && v.drapeCoefficient() < 100);
        QCOMPARE(v.controller()->nodeCount(), r->drape->metrics.node_count);
        const QVariantMap m = v.controller()->results();
        QCOMPARE(m.value("drapeCoefficientPercent").toDouble(), v.drapeCoefficient());
        QCOMPARE(v.controller()->vertexPositions().size(), int(x.rows()));

        // The command line on the same input: the same rest state (to the OBJ's 9 digits) and D.
        const QString out = m_tmp.filePath("cli");
        QProcess cli;
        cli.start(QStringLiteral(DRAPE_CLI_EXE), {"simulate", "--fabric", "cotton", "--grid", "25", "--tolerance", "1e-6",
                                                 "--out", out, "--json"});
        QVERIFY(cli.waitForFinished(300000));
        QVERIFY2(cli.exitCode() == 0, cli.readAllStandardError().constData());
        const cloth::Positions xc = readObjVertices(out + "/rest.obj");
        QCOMPARE(xc.rows(), x.rows());
        const double diff = (xc - x).cwiseAbs().maxCoeff();
        QVERIFY2(diff < 1e-7, qPrintable(QStringLiteral("widget vs CLI: %1 m").arg(diff)));
        const QJsonObject summary = QJsonDocument::fromJson(cli.readAllStandardOutput()).object();
        const double dCli = summary.value("metrics").toObject().value("drape_coefficient_percent").toDouble(
            summary.value("drape_coefficient_percent").toDouble(-1));
        QVERIFY2(std::abs(dCli - v.drapeCoefficient()) < 1e-6, qPrintable(QStringLiteral("D %1 vs %2").arg(dCli).arg(v.drapeCoefficient())));
        QVERIFY(QFile::exists(out + "/rest.png"));
    }

    void garmentOnAnImportedBodyWithALibraryFabric()
    {
        const QString bodyFile = m_tmp.filePath("body.obj");
        writeCylinderObj(bodyFile, 0.12, 1.0, 48);
        // The garment: a 0.5 m square sheet 5 cm above the body, its centre vertex pinned (a CAD's "waist").
        const int n = 15;
        const double side = 0.5, z0 = 1.05;
        drape::widget::GarmentMesh g;
        g.X.resize(n * n, 3);
        g.F.resize(2 * (n - 1) * (n - 1), 3);
        for (int j = 0; j < n; ++j)
            for (int i = 0; i < n; ++i) g.X.row(j * n + i) << -side / 2 + side * i / (n - 1), -side / 2 + side * j / (n - 1), z0;
        int t = 0;
        for (int j = 0; j + 1 < n; ++j)
            for (int i = 0; i + 1 < n; ++i) {
                const int a = j * n + i;
                g.F.row(t++) << a, a + 1, a + n + 1;
                g.F.row(t++) << a, a + n + 1, a + n;
            }
        g.pinned = {(n / 2) * n + n / 2};

        DrapeView v;
        v.resize(480, 360);
        v.show();
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        v.setLibraryPath(m_library);
        v.setFabricPreset(QStringLiteral("Silk (class preset)"));
        v.setBodyFile(bodyFile);
        v.setGarmentMesh(g);
        QCOMPARE(v.clothShape(), Drape::GarmentMesh);
        v.setRestResidual(1e-5);
        QSignalSpy results(&v, &DrapeView::resultsReady);
        v.drapeToRest();
        QTRY_VERIFY_WITH_TIMEOUT(results.count() > 0 || errors.count() > 0, 300000);
        QVERIFY2(errors.isEmpty(), errors.isEmpty() ? "" : qPrintable(errors.first().at(0).toString()));
        const auto r = v.lastResults();
        QVERIFY(r && r->penetration && !r->drape);
        QVERIFY(v.controller()->body());
        QVERIFY(v.controller()->scene()->item("body")); // drawn
        QCOMPARE(r->penetration->inside, 0);
        QVERIFY2(r->penetration->min_distance > -1e-4, qPrintable(QString::number(r->penetration->min_distance)));
        QVERIFY(std::isnan(v.drapeCoefficient()));
        const cloth::Positions x = v.positions();
        // It draped: the corners hang well below the top of the body, the pinned centre stayed.
        QVERIFY(x.col(2).minCoeff() < 0.9);
        QCOMPARE((x.row(g.pinned.front()) - g.X.row(g.pinned.front())).norm(), 0.0);

        // The same input through the engine alone.
        const fabric::FabricPreset silk = library::resolve_fabric("silk");
        auto body = std::make_shared<const importers::Mannequin>(importers::load_mannequin(bodyFile.toStdString()));
        cloth::ClothMesh mesh = cloth::make_triangle_mesh(g.X, g.F);
        cloth::ClothModel model = cloth::make_model(mesh, silk.params, silk.model);
        cloth::ClothSystem sys(std::move(mesh), std::move(model));
        sys.set_pinned(g.pinned.front(), true);
        sys.add_collider(body->contact);
        sys.add_collider(std::make_shared<cloth::PlaneCollider>(Eigen::Vector3d(0, 0, body->bounds.min.z()), Eigen::Vector3d::UnitZ()));
        cloth::RestOptions ro;
        ro.residual = 1e-5;
        const cloth::SolverStatus st = cloth::run_to_rest(sys, ro);
        QVERIFY(st.converged());
        const double diff = (sys.x - x).cwiseAbs().maxCoeff();
        QVERIFY2(diff < 1e-9, qPrintable(QStringLiteral("widget vs engine: %1 m").arg(diff)));
    }

    void cancelStopsADrape()
    {
        DrapeView v;
        v.setFabricPreset(QStringLiteral("denim")); // a starter's short name
        v.setGridSize(81);
        v.setRestResidual(1e-9);
        QSignalSpy running(&v, &DrapeView::runningChanged);
        v.drapeToRest();
        QTRY_VERIFY_WITH_TIMEOUT(v.controller()->running(), 30000);
        v.cancel();
        QTRY_VERIFY_WITH_TIMEOUT(!v.controller()->running(), 30000);
        QVERIFY(!v.lastResults());
    }

private:
    QTemporaryDir m_tmp;
    QString m_library;
};

QTEST_MAIN(TstDrapeApi)
#include "tst_drape_api.moc"
