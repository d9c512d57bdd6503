// The fitting demo under Xvfb: the MakeHuman mannequin comes in standing on the
// floor at human size, a circular skirt drapes on it without passing through
// the body, and the screenshot shows the cloth around the hips.
#include "importers/garment_metrics.hpp"
#include "importers/garment_scene.hpp"
#include "demo/main_window.hpp"
#include "widget/drape_controller.hpp"
#include "widget/scene.hpp"

#include <Eigen/Geometry>

#include <QCheckBox>
#include <QComboBox>
#include <QFile>
#include <QImage>
#include <QJsonDocument>
#include <QJsonObject>
#include <QJsonArray>
#include <QDir>
#include <QProcess>
#include <QTemporaryDir>
#include <QSignalSpy>
#include <QTest>

#include <memory>

using namespace drape;

class TstDemo : public QObject {
    Q_OBJECT
private slots:
    void initTestCase();
    void mannequinStandsOnFloor();
    void waistIsATorsoSection();
    void annulusPanel();
    void opensOnTheSceneItsControlsName();
    void skirtDrapesOnBody();
    void scriptedRunWritesScreenshot();
    void fitRefusesAFolderWithoutRecords();

private:
    static int clothPixels(const QImage& img, const QRect& r, const QColor& cloth);
    QTemporaryDir m_tmp;
    std::shared_ptr<const importers::Mannequin> m_body;
};

void TstDemo::initTestCase()
{
    if (!QFile::exists(QString::fromStdString(importers::default_mannequin_path())))
        QSKIP("assimp-testmodels is not installed (cmake/setup-deps.sh installs it)");
    QVERIFY(m_tmp.isValid());
    // A library that does not exist: the demo falls back to the starter presets,
    // so the test does not depend on the user's library.
    qputenv("DRAPE_LIBRARY", m_tmp.filePath("no-library.sqlite").toUtf8());
    m_body = std::make_shared<importers::Mannequin>(importers::load_mannequin(importers::default_mannequin_path()));
}

void TstDemo::mannequinStandsOnFloor()
{
    const auto& b = m_body->bounds;
    // A standing adult: 1.5-1.95 m tall, feet on z = 0, narrower than tall in both directions.
    QVERIFY2(m_body->height() > 1.5 && m_body->height() < 1.95, qPrintable(QString::number(m_body->height())));
    QCOMPARE(b.min.z(), 0.0);
    // Up is z: the height is the largest extent (arms spread in MakeHuman's A pose
    // stay narrower than the height) and the body is much less deep than tall.
    QVERIFY(b.size().z() > b.size().x());
    QVERIFY(b.size().z() > 2 * b.size().y());
    QVERIFY(std::abs(b.min.x() + b.max.x()) < 1e-9);
    QVERIFY(std::abs(b.min.y() + b.max.y()) < 1e-9);
}

void TstDemo::waistIsATorsoSection()
{
    const importers::Girth w = importers::find_waist(*m_body);
    QCOMPARE(w.rays_hit, w.rays);
    const double h = m_body->height();
    QVERIFY(w.z > 0.56 * h && w.z < 0.66 * h);
    // A torso, not the whole section with the arms: a waist girth 2 pi r of 0.5-1.3 m.
    QVERIFY2(w.mean_radius > 0.08 && w.mean_radius < 0.2, qPrintable(QString::number(w.mean_radius)));
    // The hips (20 cm lower) are wider than the waist.
    const importers::Girth hips = importers::measure_girth(*m_body, w.z - 0.2);
    QVERIFY(hips.mean_radius > w.mean_radius);
    // The centre is inside the body.
    QVERIFY(m_body->collider->signed_distance(Eigen::Vector3d(w.centre.x(), w.centre.y(), w.z)) < 0);
}

void TstDemo::annulusPanel()
{
    const importers::Panel p = importers::make_annulus(Eigen::Vector2d(0.1, -0.2), 1.0, 0.15, 0.6, 32, 10);
    QCOMPARE(int(p.X.rows()), 32 * 11);
    QCOMPARE(int(p.F.rows()), 2 * 32 * 10);
    QCOMPARE(int(p.waistband.size()), 32);
    double area = 0;
    for (Eigen::Index t = 0; t < p.F.rows(); ++t) {
        const Eigen::Vector3d a = p.X.row(p.F(t, 0)), b = p.X.row(p.F(t, 1)), c = p.X.row(p.F(t, 2));
        const double z = (b - a).cross(c - a).z();
        QVERIFY(z > 0); // counter-clockwise from +z
        area += z / 2;
    }
    // The polygonal annulus is a little smaller than the round one (inscribed polygons).
    const double exact = 3.14159265358979 * (0.6 * 0.6 - 0.15 * 0.15);
    QVERIFY(area < exact && area > 0.98 * exact);
    for (int v : p.waistband) QVERIFY(std::abs((p.X.row(v).head<2>() - Eigen::RowVector2d(0.1, -0.2)).norm() - 0.15) < 1e-12);
    QVERIFY_THROWS_EXCEPTION(std::exception, importers::make_annulus(Eigen::Vector2d::Zero(), 0, 0.5, 0.4, 32, 4));
}

int TstDemo::clothPixels(const QImage& img, const QRect& r, const QColor& cloth)
{
    int n = 0;
    const QRect rr = r.intersected(img.rect());
    for (int y = rr.top(); y <= rr.bottom(); ++y)
        for (int x = rr.left(); x <= rr.right(); ++x) {
            const QColor c = img.pixelColor(x, y);
            // Same hue family as the cloth (shading changes the value, not the hue much),
            // and saturated: the skin, floor and background are not.
            if (c.hsvSaturation() > 90 && c.value() > 30) {
                const int dh = std::abs(c.hsvHue() - cloth.hsvHue());
                if (std::min(dh, 360 - dh) < 25) ++n;
            }
        }
    return n;
}

void TstDemo::opensOnTheSceneItsControlsName()
{
    // Before Drape is pressed the view shows what the controls name: the skirt's
    // flat pattern around the mannequin, not the widget's default drapemeter disc;
    // a changed choice shows at once.
    demo::MainWindow w(demo::DemoOptions{});
    w.resize(900, 700);
    w.show();
    QVERIFY(QTest::qWaitForWindowExposed(&w));
    QCOMPARE(w.garmentBox()->currentData().toString(), QStringLiteral("skirt"));
    QVERIFY(!w.draping());
    auto* c = w.viewA()->controller();
    QCOMPARE(c->clothShape(), widget::Drape::Skirt);
    // The scene is built off the UI thread: the mannequin and the pattern arrive.
    QTRY_VERIFY_WITH_TIMEOUT(!c->colliders().isEmpty() && c->vertexCount() > 0, 30000);
    QVERIFY(c->scene()->title().startsWith(QStringLiteral("skirt")));
    const int table = w.garmentBox()->findData(QStringLiteral("tablecloth"));
    QVERIFY(table >= 0);
    w.garmentBox()->setCurrentIndex(table);
    QCOMPARE(c->clothShape(), widget::Drape::Tablecloth);
    QVERIFY(!w.draping());
}

void TstDemo::skirtDrapesOnBody()
{
    demo::MainWindow w(demo::DemoOptions{});
    w.resize(900, 700);
    w.show();
    QVERIFY(QTest::qWaitForWindowExposed(&w));
    QVERIFY(w.fabrics().size() >= 2);
    QCOMPARE(w.garmentBox()->currentData().toString(), QStringLiteral("skirt"));
    const int cotton = w.findFabric("cotton");
    QVERIFY(cotton >= 0);
    w.fabricBoxA()->setCurrentIndex(cotton);

    QSignalSpy done(&w, &demo::MainWindow::drapeFinished);
    QString err;
    QVERIFY2(w.startDrape(&err), qPrintable(err));
    QVERIFY(w.draping());
    QVERIFY(done.wait(20 * 60 * 1000));
    QVERIFY2(done.first().at(0).toBool(), qPrintable(done.first().at(1).toString()));

    demo::FittingView* v = w.viewA();
    const cloth::SolverStatus& st = v->lastStatus();
    QVERIFY2(st.outcome == cloth::SolverStatus::Outcome::Converged ||
                 st.outcome == cloth::SolverStatus::Outcome::NotConverged,
             cloth::to_string(st.outcome).c_str());
    QVERIFY(v->mannequin());
    QVERIFY(v->garment() == demo::GarmentChoice::Skirt);
    // The scene the view draped, rebuilt headless from the same body and fabric (deterministic).
    const importers::Scene ref = importers::make_skirt_scene(v->mannequin(), w.fabrics()[std::size_t(cotton)].preset);
    const importers::Scene* s = &ref;
    const cloth::Positions x = v->lastPositions();
    QCOMPARE(int(x.rows()), s->system->vertex_count());
    std::vector<int> pinned;
    for (int i = 0; i < s->system->vertex_count(); ++i)
        if (s->system->pinned(i)) pinned.push_back(i);
    QVERIFY(v->controller()->currentMesh()->pinnedAtStart == pinned); // the waistband
    QVERIFY(x.allFinite());

    // The test: no cloth vertex inside the body at rest.
    const importers::Penetration pen = importers::body_penetration(*s->mannequin, x);
    QVERIFY2(pen.inside == 0, qPrintable(QStringLiteral("%1 vertices inside, deepest %2 m")
                                             .arg(pen.inside).arg(pen.min_distance)));
    // The skirt hangs (the flat pattern fell) and rests on the body: its closest
    // vertex touches it within a few millimetres (contact, not floating).
    QVERIFY(x.col(2).minCoeff() < s->waist.z - 0.25);
    QVERIFY2(pen.min_distance < 0.01, qPrintable(QString::number(pen.min_distance)));
    // The waistband stayed where it was pinned.
    for (int i = 0; i < s->system->vertex_count(); ++i)
        if (s->system->pinned(i)) QVERIFY((x.row(i) - s->system->mesh().X.row(i)).norm() < 1e-12);
    // Self-collision (on in every garment scene): no fold passes through another.
    const importers::GarmentMetrics gm = importers::garment_metrics(x, s->system->mesh().F, s->system->model().pinned,
                                                                    s->mannequin.get(), s->waist.centre);
    QCOMPARE(gm.self_intersections, 0L);

    // The screenshot shows the cloth around the hips: project the hip point into the view.
    const QImage img = w.screenshot();
    QVERIFY(!img.isNull());
    QVERIFY(img.save(m_tmp.filePath("skirt.png")));
    const double hipZ = s->waist.z - 0.2;
    double px = 0, py = 0;
    const double dpr = img.devicePixelRatio();
    QVERIFY(v->camera().project(Eigen::Vector3d(s->waist.centre.x(), s->waist.centre.y(), hipZ),
                                img.width() / dpr, img.height() / dpr, px, py));
    const QRect hips(int(px * dpr) - 60, int(py * dpr) - 40, 120, 80);
    const QColor cloth(0xb0, 0x3a, 0x48);
    const int near = clothPixels(img, hips, cloth);
    QVERIFY2(near > hips.width() * hips.height() / 3, qPrintable(QStringLiteral("%1 cloth pixels near the hips").arg(near)));
    // And the head (above the waistband) is not covered.
    double hx = 0, hy = 0;
    QVERIFY(v->camera().project(Eigen::Vector3d(0, 0, s->mannequin->bounds.max.z() - 0.12), img.width() / dpr,
                                img.height() / dpr, hx, hy));
    if (hy > 0) QCOMPARE(clothPixels(img, QRect(int(hx * dpr) - 20, int(hy * dpr) - 20, 40, 40), cloth), 0);
}

void TstDemo::scriptedRunWritesScreenshot()
{
    // The executable's scripted mode: a tablecloth on the round table, in denim
    // (11 s to rest; silk, the limpest starter, takes 19 s).
    const QString exe = QCoreApplication::applicationDirPath() + "/../bin/drape-demo";
    if (!QFile::exists(exe)) QSKIP("drape-demo is not built next to the tests");
    const QString png = m_tmp.filePath("table.png"), json = m_tmp.filePath("table.json");
    QProcess p;
    p.setProcessChannelMode(QProcess::ForwardedErrorChannel);
    p.start(exe, {"--script", "tablecloth", "--fabric", "denim", "--screenshot", png, "--json", json, "--size", "700x560"});
    QVERIFY(p.waitForFinished(20 * 60 * 1000));
    QCOMPARE(p.exitCode(), 0);
    QImage img(png);
    QVERIFY(!img.isNull());
    QFile f(json);
    QVERIFY(f.open(QIODevice::ReadOnly));
    const QJsonObject o = QJsonDocument::fromJson(f.readAll()).object()["views"].toArray().at(0).toObject();
    QCOMPARE(o["garment"].toString(), QStringLiteral("tablecloth"));
    QVERIFY(o["fabric"].toString().contains("Denim", Qt::CaseInsensitive));
    // The cloth covers the table top (0.75 m) and hangs below it, above the floor.
    QVERIFY(o["cloth_max_z_m"].toDouble() > 0.75);
    QVERIFY(o["cloth_min_z_m"].toDouble() < 0.6);
    QVERIFY(o["cloth_min_z_m"].toDouble() >= 0.0);
    QVERIFY(clothPixels(img, img.rect(), QColor(0xb0, 0x3a, 0x48)) > img.width() * img.height() / 50);
}

void TstDemo::fitRefusesAFolderWithoutRecords()
{
    // --fit on a folder that is not there, and on one with no meta.json in it or its
    // subfolders: exit 1 and a message naming the folder, before any fit starts.
    const QString exe = QCoreApplication::applicationDirPath() + "/../bin/drape-demo";
    if (!QFile::exists(exe)) QSKIP("drape-demo is not built next to the tests");
    const QString empty = m_tmp.filePath("no-records");
    QVERIFY(QDir().mkpath(empty + "/sub"));
    const QString missing = m_tmp.filePath("not-there");
    for (const QString& dir : {missing, empty}) {
        QProcess p;
        p.start(exe, {"--fit", dir, "--screenshot", m_tmp.filePath("fit.png")});
        QVERIFY(p.waitForFinished(60 * 1000));
        QCOMPARE(p.exitCode(), 1);
        const QString err = QString::fromLocal8Bit(p.readAllStandardError());
        QVERIFY2(err.contains(dir), qPrintable(err));
        QVERIFY2(err.contains(dir == missing ? "no such folder" : "no record (meta.json)"), qPrintable(err));
        QVERIFY(!QFile::exists(m_tmp.filePath("fit.png")));
    }
}

QTEST_MAIN(TstDemo)
#include "tst_demo.moc"
