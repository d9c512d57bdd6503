// DrapeView / DrapeController: properties follow Qt's setter convention, the
// commands reach the simulation, bad input becomes errorOccurred and leaves the
// widget usable, the QML types load in a Qt Quick host.
#include "widget/drape_qml.hpp"
#include "widget/drape_view.hpp"

#include "engine/cloth/drape.hpp"
#include "engine/cloth/mesh.hpp"
#include "engine/cloth/params.hpp"

#include <QFile>
#include <QJsonArray>
#include <QJsonDocument>
#include <QJsonObject>
#include <QQmlComponent>
#include <QQmlEngine>
#include <QQuickItem>
#include <QSignalSpy>
#include <QTemporaryDir>
#include <QTest>

#include <cmath>

using drape::widget::DrapeController;
using drape::widget::DrapeView;
namespace Drape = drape::widget::Drape;

class TstDrapeView : public QObject {
    Q_OBJECT

    /// Waits until the view shows a cloth built from the current properties.
    static bool waitForCloth(DrapeView& v)
    {
        QSignalSpy mesh(v.controller(), &DrapeController::meshChanged);
        v.createCloth();
        if (!mesh.wait(30000)) return false;
        QSignalSpy frame(v.controller(), &DrapeController::frameApplied);
        return v.controller()->currentFrame() || frame.wait(30000);
    }

    /// Waits for the next frame that shows the simulation after all commands sent so far.
    static bool waitForFrame(DrapeView& v)
    {
        QSignalSpy frame(v.controller(), &DrapeController::frameApplied);
        return frame.wait(30000);
    }

private slots:
    void defaults()
    {
        DrapeView v;
        QCOMPARE(v.sampleDiameter(), 300.0);
        QCOMPARE(v.discDiameter(), 150.0);
        QCOMPARE(v.gridSize(), 40);
        QCOMPARE(v.integrator(), Drape::Static);
        QCOMPARE(v.clothShape(), Drape::Disc);
        QCOMPARE(v.viewPreset(), Drape::Iso);
        QCOMPARE(v.running(), false);
        QVERIFY(v.texture().isEmpty());
        QVERIFY(v.fabricPreset().isEmpty());
    }

    void settersFollowQtConvention()
    {
        DrapeView v;
        QSignalSpy grid(&v, &DrapeView::gridSizeChanged);
        QSignalSpy dia(&v, &DrapeView::sampleDiameterChanged);
        QSignalSpy disc(&v, &DrapeView::discDiameterChanged);
        QSignalSpy integ(&v, &DrapeView::integratorChanged);
        QSignalSpy view(&v, &DrapeView::viewPresetChanged);
        QSignalSpy errors(&v, &DrapeView::errorOccurred);

        v.setGridSize(24);
        v.setGridSize(24); // unchanged: no second signal
        QCOMPARE(grid.count(), 1);
        QCOMPARE(grid.at(0).at(0).toInt(), 24);
        QCOMPARE(v.gridSize(), 24);

        v.setSampleDiameter(240.0);
        v.setSampleDiameter(240.0);
        QCOMPARE(dia.count(), 1);
        QCOMPARE(v.sampleDiameter(), 240.0);
        v.setDiscDiameter(180.0);
        QCOMPARE(disc.count(), 1);

        v.setIntegrator(Drape::RK4);
        v.setIntegrator(Drape::RK4);
        QCOMPARE(integ.count(), 1);
        QCOMPARE(v.integrator(), Drape::RK4);

        v.setViewPreset(Drape::Top);
        QCOMPARE(view.count(), 1);
        QCOMPARE(errors.count(), 0);

        // The property is also reachable through the meta-object (Designer, QUiLoader, QML).
        QVERIFY(v.setProperty("gridSize", 30));
        QCOMPARE(v.gridSize(), 30);
        QCOMPARE(grid.count(), 2);
        // The choices are enums: Designer's drop-downs, uic's constants, QML's Drape.Static.
        const QMetaObject* mo = v.metaObject();
        for (const char* name : {"integrator", "viewPreset", "clothShape"}) {
            const QMetaProperty p = mo->property(mo->indexOfProperty(name));
            QVERIFY2(p.isEnumType(), name);
            QVERIFY2(p.isDesignable(), name);
            QVERIFY2(p.enumerator().isValid() && p.enumerator().keyCount() >= 2, name);
        }
        QVERIFY(v.setProperty("integrator", QStringLiteral("Static")));
        QCOMPARE(v.integrator(), Drape::Static);
        QCOMPARE(QString::fromLatin1(mo->property(mo->indexOfProperty("integrator")).enumerator().valueToKey(Drape::Implicit)),
                 QStringLiteral("Implicit"));
    }

    void badValuesAreRejectedWithAnError()
    {
        DrapeView v;
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        QSignalSpy grid(&v, &DrapeView::gridSizeChanged);
        v.setGridSize(2);
        QCOMPARE(v.gridSize(), 40);
        QCOMPARE(grid.count(), 0);
        QCOMPARE(errors.count(), 1);
        QVERIFY(errors.at(0).at(0).toString().contains(QStringLiteral("gridSize")));

        v.setIntegrator(static_cast<Drape::Integrator>(42));
        QCOMPARE(v.integrator(), Drape::Static);
        QCOMPARE(errors.count(), 2);
        QVERIFY(errors.at(1).at(0).toString().contains(QStringLiteral("integrator")));

        v.setSampleDiameter(std::nan(""));
        v.setViewPreset(static_cast<Drape::ViewPreset>(42));
        v.setTimeStep(-1.0);
        QCOMPARE(errors.count(), 5);
        QCOMPARE(v.sampleDiameter(), 300.0);
        QCOMPARE(v.viewPreset(), Drape::Iso);
        QCOMPARE(v.timeStep(), 0.0);

        // A disc wider than the specimen passes the setter but not the engine's
        // set-up check: error, and the previous cloth stays.
        QVERIFY(waitForCloth(v));
        const int before = v.controller()->vertexCount();
        v.setDiscDiameter(400.0);
        QVERIFY(errors.wait(30000));
        QCOMPARE(v.controller()->vertexCount(), before);
    }

    void buildsTheRequestedGrid()
    {
        DrapeView v;
        v.setGridSize(25);
        QVERIFY(waitForCloth(v));
        drape::cloth::DrapeSetup su;
        su.grid = 25;
        const auto sys = drape::cloth::make_drape_system(drape::cloth::FabricParams(), su);
        QCOMPARE(v.controller()->vertexCount(), sys->vertex_count());
        QCOMPARE(v.controller()->clothGeometry()->vertexCount(), sys->vertex_count());
        QCOMPARE(v.controller()->clothGeometry()->triangleCount(), int(sys->mesh().F.rows()));
        // Colliders of the drapemeter: pedestal and floor.
        QStringList kinds;
        for (const QVariant& c : v.controller()->colliders()) kinds << c.toMap().value("kind").toString();
        QVERIFY(kinds.contains("pedestal"));
        QVERIFY(kinds.contains("plane"));
    }

    void squareClothAndSphereCollider()
    {
        DrapeView v;
        v.setGridSize(12);
        v.setClothShape(Drape::Square);
        QVERIFY(waitForCloth(v));
        QCOMPARE(v.controller()->vertexCount(), 12 * 12); // a full grid: nothing cut away
        QSignalSpy colliders(v.controller(), &DrapeController::collidersChanged);
        v.controller()->addSphereCollider(QVector3D(0.1f, 0.0f, -0.05f), 0.03);
        QVERIFY(colliders.wait(30000));
        int spheres = 0;
        for (const QVariant& c : v.controller()->colliders()) {
            const QVariantMap m = c.toMap();
            if (m.value("kind").toString() != QLatin1String("sphere")) continue;
            ++spheres;
            // Drawn where it is: world (0.1, 0, -0.05) is scene (0.1, -0.05, 0); #Sphere has radius 50.
            QVERIFY((m.value("position").value<QVector3D>() - QVector3D(0.1f, -0.05f, 0.0f)).length() < 1e-6f);
            QVERIFY(std::abs(m.value("scale").value<QVector3D>().x() * 50.0f - 0.03f) < 1e-6f);
        }
        QCOMPARE(spheres, 1);
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        v.controller()->addSphereCollider(QVector3D(0, 0, 0), -1.0);
        v.setClothShape(static_cast<Drape::ClothShape>(42));
        QCOMPARE(errors.count(), 2);
        v.controller()->clearExtraColliders();
        QVERIFY(colliders.wait(30000));
        for (const QVariant& c : v.controller()->colliders()) QVERIFY(c.toMap().value("kind").toString() != "sphere");
    }

    void missingTextureAndMalformedPresetLeaveTheWidgetUsable()
    {
        QTemporaryDir dir;
        QVERIFY(dir.isValid());
        DrapeView v;
        v.setIntegrator(Drape::Symplectic); // a live fall, whose simulated time advances
        v.setGridSize(12);
        QVERIFY(waitForCloth(v));
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        QSignalSpy tex(&v, &DrapeView::textureChanged);

        const QString missing = dir.filePath("no-such-photo.png");
        v.setTexture(missing);
        QCOMPARE(errors.count(), 1);
        QVERIFY(errors.at(0).at(0).toString().contains(missing));
        QVERIFY(v.texture().isEmpty());
        QCOMPARE(tex.count(), 0);

        // Not an image at all.
        const QString junk = dir.filePath("junk.bmp");
        {
            QFile f(junk);
            QVERIFY(f.open(QIODevice::WriteOnly));
            f.write("this is not a bitmap");
        }
        v.setTexture(junk);
        QCOMPARE(errors.count(), 2);
        QVERIFY(v.texture().isEmpty());

        const QString bad = dir.filePath("bad-preset.json");
        {
            QFile f(bad);
            QVERIFY(f.open(QIODevice::WriteOnly));
            f.write("{ \"format\": \"drapekit-fabric\", \"version\": 1, \"area_density_kg_m2\": ");
        }
        v.setFabricPreset(bad);
        QCOMPARE(errors.count(), 3);
        QVERIFY(errors.at(2).at(0).toString().contains(bad));
        QVERIFY(v.fabricPreset().isEmpty());
        v.setFabricPreset(dir.filePath("missing-preset.json"));
        QCOMPARE(errors.count(), 4);

        // Still usable: a real texture loads, the cloth steps.
        const QString png = dir.filePath("check.png");
        QImage img(64, 64, QImage::Format_RGB32);
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) img.setPixel(x, y, ((x / 8 + y / 8) % 2) ? 0xffffffu : 0xff203080u);
        QVERIFY(img.save(png));
        v.setTexture(png);
        QCOMPARE(v.texture(), png);
        QCOMPARE(tex.count(), 1);
        QVERIFY(v.controller()->hasTexture());
        const double t0 = v.controller()->simulatedTime();
        v.setTimeStep(1e-4);
        v.step();
        QVERIFY(waitForFrame(v));
        QVERIFY(v.controller()->simulatedTime() > t0);
        QCOMPARE(errors.count(), 4);
    }

    void presetsSaveAndLoad()
    {
        QTemporaryDir dir;
        DrapeView v;
        v.setGridSize(12);
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        QSignalSpy preset(&v, &DrapeView::fabricPresetChanged);
        // Edit one parameter through the table, save, load into another view.
        const auto& spec = drape::cloth::spec(drape::cloth::Param::AreaDensity);
        const QString key = QString::fromUtf8(spec.key.data(), qsizetype(spec.key.size()));
        const double rho = 0.5 * (spec.lower + spec.upper);
        QVERIFY(v.controller()->setFabricParameter(key, rho));
        QVERIFY(!v.controller()->setFabricParameter(key, spec.upper * 10)); // out of bounds
        QVERIFY(!v.controller()->setFabricParameter(QStringLiteral("no_such_key"), 1.0));
        QCOMPARE(errors.count(), 2);
        const QString path = dir.filePath("edited.json");
        QVERIFY(v.saveFabricPreset(path));

        DrapeView w;
        w.setFabricPreset(path);
        QCOMPARE(w.fabricPreset(), path);
        const QVariantList params = w.controller()->fabricParameters();
        QCOMPARE(params.size(), int(drape::cloth::param_table().size()));
        bool found = false;
        for (const QVariant& p : params) {
            const QVariantMap m = p.toMap();
            if (m.value("key").toString() == key) {
                QCOMPARE(m.value("value").toDouble(), rho);
                found = true;
            }
        }
        QVERIFY(found);
        QVERIFY(!v.saveFabricPreset(dir.filePath("no/such/dir/x.json")));
        QCOMPARE(errors.count(), 3);

        // The built-in seed preset loads by name.
        v.setFabricPreset(QStringLiteral("seed-table1"));
        QCOMPARE(preset.count(), 1);
        QCOMPARE(errors.count(), 3);
    }

    void playPauseStepReset()
    {
        DrapeView v;
        v.setIntegrator(Drape::Symplectic); // a live fall, whose simulated time advances
        v.setGridSize(12);
        QVERIFY(waitForCloth(v));
        const drape::cloth::Positions x0 = v.controller()->currentFrame()->x;

        QSignalSpy running(&v, &DrapeView::runningChanged);
        QSignalSpy progress(&v, &DrapeView::progress);
        v.play();
        QVERIFY(v.running());
        QVERIFY(progress.wait(30000));
        QTRY_VERIFY_WITH_TIMEOUT(v.controller()->simulatedTime() > 0.01, 30000);
        v.pause();
        QVERIFY(!v.running());
        QVERIFY(running.count() >= 2);
        QVERIFY(waitForFrame(v)); // pause publishes the state it stopped at
        QTest::qWait(300);        // frames sent before the pause arrived have drained
        const double tPaused = v.controller()->simulatedTime();
        // Paused: time does not advance.
        QTest::qWait(300);
        QCOMPARE(v.controller()->simulatedTime(), tPaused);

        // One step advances by exactly the time step.
        v.setTimeStep(2e-5);
        v.step();
        QVERIFY(waitForFrame(v));
        QVERIFY(std::abs(v.controller()->simulatedTime() - (tPaused + 2e-5)) < 1e-12);

        // The cloth fell: reset brings back the start.
        const drape::cloth::Positions moved = v.controller()->currentFrame()->x;
        QVERIFY((moved - x0).norm() > 1e-4);
        v.reset();
        QVERIFY(waitForFrame(v));
        QCOMPARE(v.controller()->simulatedTime(), 0.0);
        QVERIFY((v.controller()->currentFrame()->x - x0).norm() < 1e-12);
    }

    void pinsAndMassesReachTheSimulation()
    {
        DrapeView v;
        v.setIntegrator(Drape::Symplectic); // a live fall, whose simulated time advances
        v.setGridSize(12);
        QVERIFY(waitForCloth(v));
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        const auto& b = v.controller()->currentMesh()->boundary;
        int hem = -1;
        for (int i = 0; i < int(b.size()); ++i)
            if (b[std::size_t(i)]) hem = i;
        QVERIFY(hem >= 0);
        const Eigen::Vector3d start = v.controller()->currentFrame()->x.row(hem);
        v.controller()->setPinned(hem, true);
        QVERIFY(v.controller()->isPinned(hem));
        v.controller()->setVertexMass(0, 0.0125);
        v.controller()->setVertexMass(0, -1.0);  // error
        v.controller()->setPinned(100000, true); // error
        QCOMPARE(errors.count(), 2);
        v.play();
        QTRY_VERIFY_WITH_TIMEOUT(v.controller()->simulatedTime() > 0.05, 30000);
        v.pause();
        QVERIFY(waitForFrame(v));
        QTest::qWait(300); // frames sent before the pause have drained
        const auto f = v.controller()->currentFrame();
        QVERIFY(v.controller()->simulatedPinnedVertices().contains(hem));
        // A pinned hem vertex stays where it was while the rest of the hem falls.
        QVERIFY((Eigen::Vector3d(f->x.row(hem)) - start).norm() < 1e-12);
        double lowest = 0;
        for (int i = 0; i < int(b.size()); ++i)
            if (b[std::size_t(i)]) lowest = std::min(lowest, f->x(i, 2));
        QVERIFY(lowest < start.z() - 1e-3);
        QCOMPARE(v.controller()->vertexMass(0), 0.0125);
        QCOMPARE(v.controller()->pinnedPositions().size(), 1);
        v.controller()->setPinned(hem, false);
        QTRY_VERIFY_WITH_TIMEOUT(!v.controller()->simulatedPinnedVertices().contains(hem), 10000);
        QCOMPARE(errors.count(), 2);
    }

    void restReachedAndResultsSaved()
    {
        QTemporaryDir dir;
        DrapeView v;
        v.setGridSize(16);
        v.setIntegrator(Drape::Static);
        QVERIFY(waitForCloth(v));
        QSignalSpy rest(&v, &DrapeView::restReached);
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        v.play();
        QVERIFY(rest.wait(60000));
        QTRY_VERIFY_WITH_TIMEOUT(!v.running(), 10000);
        QCOMPARE(errors.count(), 0);

        QSignalSpy saved(&v, &DrapeView::resultsSaved);
        const QString json = dir.filePath("state.json");
        v.saveResults(json);
        QVERIFY(saved.wait(30000));
        QFile jf(json);
        QVERIFY(jf.open(QIODevice::ReadOnly));
        const QJsonObject j = QJsonDocument::fromJson(jf.readAll()).object();
        QCOMPARE(j.value("format").toString(), QStringLiteral("drapekit-widget-state"));
        const double dc = j.value("results").toObject().value("drape_coefficient_percent").toDouble(-1);
        QVERIFY(dc > 0 && dc < 100); // a draped specimen, neither flat nor collapsed
        QCOMPARE(j.value("state").toObject().value("vertices").toInt(), v.controller()->vertexCount());
        QFile of(saved.at(0).at(1).toString());
        QVERIFY(of.open(QIODevice::ReadOnly));
        int vlines = 0, flines = 0;
        while (!of.atEnd()) {
            const QByteArray line = of.readLine();
            if (line.startsWith("v ")) ++vlines;
            if (line.startsWith("f ")) ++flines;
        }
        QCOMPARE(vlines, v.controller()->vertexCount());
        QCOMPARE(flines, v.controller()->clothGeometry()->triangleCount());

        v.saveResults(dir.filePath("no/such/dir/state.json"));
        QVERIFY(errors.wait(30000));
    }

    void longJobProgressCancelAndErrors()
    {
        DrapeView v;
        QSignalSpy progress(&v, &DrapeView::jobProgress);
        QSignalSpy finished(&v, &DrapeView::jobFinished);
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        QVERIFY(v.controller()->startJob("fit", [](drape::widget::JobContext& ctx) {
            ctx.report(0.5, QStringLiteral("half way"));
            while (!ctx.cancelled()) QThread::msleep(5);
        }));
        QVERIFY(v.controller()->jobRunning());
        QVERIFY(!v.controller()->startJob("second", [](drape::widget::JobContext&) {})); // one at a time
        QVERIFY(progress.wait(10000));
        QCOMPARE(progress.at(0).at(0).toDouble(), 0.5);
        v.cancelJob();
        QVERIFY(finished.wait(10000));
        QCOMPARE(finished.at(0).at(0).toBool(), false);
        QCOMPARE(finished.at(0).at(1).toString(), QStringLiteral("cancelled"));

        QVERIFY(v.controller()->startJob("fit", [](drape::widget::JobContext&) {
            throw std::runtime_error("record 'x' has no top photo");
        }));
        QVERIFY(finished.wait(10000));
        QCOMPARE(finished.at(1).at(0).toBool(), false);
        QVERIFY(errors.count() >= 2);
        QVERIFY(errors.last().at(0).toString().contains("no top photo"));
    }

    void measuredOutlineOverlay()
    {
        DrapeView v;
        QPolygonF poly;
        for (int k = 0; k < 36; ++k) poly << QPointF(0.12 * std::cos(k * M_PI / 18), 0.12 * std::sin(k * M_PI / 18));
        v.showMeasuredOutline(poly);
        QVERIFY(v.showOutlines());
        QCOMPARE(v.controller()->measuredOutline()->pointCount(), 36);
        QSignalSpy errors(&v, &DrapeView::errorOccurred);
        v.showMeasuredOutline(QPolygonF{{0, 0}, {1, 0}});
        QCOMPARE(errors.count(), 1);
    }

    void qmlTypesInAQtQuickHost()
    {
        drape::widget::registerDrapeQmlTypes();
        QQmlEngine engine;
        QQmlComponent c(&engine);
        c.setData("import QtQuick\nimport Drapekit\n"
                  "DrapeScene { width: 320; height: 240; controller: DrapeController { gridSize: 12; viewPreset: Drape.Top } }",
                  QUrl());
        std::unique_ptr<QObject> root(c.create());
        QVERIFY2(root, qPrintable(c.errorString()));
        auto* ctl = root->property("controller").value<DrapeController*>();
        QVERIFY(ctl);
        QCOMPARE(ctl->gridSize(), 12);
        QCOMPARE(ctl->viewPreset(), Drape::Top);
        QTRY_VERIFY_WITH_TIMEOUT(ctl->vertexCount() > 0, 30000);
    }
};

QTEST_MAIN(TstDrapeView)
#include "tst_drape_view.moc"
