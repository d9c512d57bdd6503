// The view renders what the simulation computed: after a drape comes to rest the
// top view shows cloth where the drape is (over the pedestal) and the
// background outside its shadow outline (computed by the engine's metric code
// from the same positions); a mouse click pins the vertex under the cursor.
#include "widget/drape_view.hpp"
#include "tests/slow_cases.hpp"

#include "engine/cloth/metrics.hpp"

#include <QQuickWidget>
#include <QSignalSpy>
#include <QTest>

#include <cmath>
#include <numbers>

using drape::widget::DrapeController;
using drape::widget::DrapeView;
namespace Drape = drape::widget::Drape;

namespace {

const QColor kBackground(40, 90, 60);
const QColor kCloth(230, 40, 40);

bool isBackground(QRgb p)
{
    return std::abs(qRed(p) - kBackground.red()) <= 6 && std::abs(qGreen(p) - kBackground.green()) <= 6 &&
           std::abs(qBlue(p) - kBackground.blue()) <= 6;
}

/// Lit red cloth: red clearly dominates whatever the shading.
bool isCloth(QRgb p)
{
    return qRed(p) > 60 && qRed(p) > 2 * qGreen(p) && qRed(p) > 2 * qBlue(p);
}

} // namespace

class TstDrapeRender : public QObject {
    Q_OBJECT

    std::unique_ptr<DrapeView> m_view;

    QImage grab()
    {
        QCoreApplication::processEvents();
        return m_view->grabFrame();
    }
    QPoint toImage(const QImage& img, const Eigen::Vector3d& p) const
    {
        const QSize s = m_view->quickWidget()->size();
        const QPointF q = m_view->controller()->projectToView(QVector3D(float(p.x()), float(p.y()), float(p.z())),
                                                              s.width(), s.height());
        return {int(std::lround(q.x() * img.width() / s.width() - 0.5)),
                int(std::lround(q.y() * img.height() / s.height() - 0.5))};
    }

private slots:
    void initTestCase()
    {
        m_view = std::make_unique<DrapeView>();
        m_view->resize(640, 480);
        m_view->setBackgroundColor(kBackground);
        m_view->setClothColor(kCloth);
        m_view->setShowColliders(false); // background everywhere the cloth is not
        m_view->setViewPreset(Drape::Top);
        // A drape to rest: in the slow entry a live fall (the symplectic integrator,
        // what a user watches), in the unit entry Newton's rest state (Static: the
        // same frames and checks, a minute less under software OpenGL).
        m_view->setGridSize(20);
        m_view->setIntegrator(drape_test::slow_cases_enabled() ? Drape::Symplectic : Drape::Static);
        m_view->show();
        QVERIFY(QTest::qWaitForWindowExposed(m_view.get()));
        QSignalSpy mesh(m_view->controller(), &DrapeController::meshChanged);
        m_view->createCloth();
        QVERIFY(mesh.wait(30000));
        QSignalSpy rest(m_view.get(), &DrapeView::restReached);
        m_view->play();
        QVERIFY(rest.wait(120000));
        QTRY_VERIFY_WITH_TIMEOUT(!m_view->running(), 10000);
        QTest::qWait(300);
    }

    void drapeIsWhereTheEngineSaysItIs()
    {
        const auto frame = m_view->controller()->currentFrame();
        const auto mesh = m_view->controller()->currentMesh();
        QVERIFY(frame && mesh);
        const QImage img = grab();
        QVERIFY(!img.isNull());
        QVERIFY(img.width() > 100);
        img.save(QDir::temp().filePath("tst_drape_render_top.png"));

        // Shadow outline and its radius per direction, from the engine's metric path.
        const auto outline = drape::cloth::shadow_outline(frame->x, mesh->F);
        const auto profile = drape::cloth::radial_profile(outline, 72);
        const double R1 = mesh->sampleRadius, R2 = mesh->discRadius;
        double rmin = R1;
        int clothHits = 0, bgHits = 0, checked = 0;
        for (int k = 0; k < profile.size(); ++k) {
            const double th = profile.theta(k), r = profile.r[std::size_t(k)];
            QVERIFY(std::isfinite(r));
            rmin = std::min(rmin, r);
            // On the pedestal top: the cloth lies there.
            const QPoint in = toImage(img, {0.7 * R2 * std::cos(th), 0.7 * R2 * std::sin(th), 0.0});
            // Outside the shadow outline at the pedestal-top height: a ray through it
            // only moves away from the axis as it descends, so it never meets cloth.
            const double ro = r + 0.012;
            const QPoint out = toImage(img, {ro * std::cos(th), ro * std::sin(th), 0.0});
            QVERIFY(img.rect().contains(in) && img.rect().contains(out));
            clothHits += isCloth(img.pixel(in));
            bgHits += isBackground(img.pixel(out));
            ++checked;
        }
        QCOMPARE(clothHits, checked);
        QCOMPARE(bgHits, checked);
        // It is a drape, not a flat sheet: the outline comes well inside the cut circle,
        // and the pixels between the outline and the flat radius there are background.
        QVERIFY(rmin < R1 - 0.02);
        // The image corners are background too.
        QVERIFY(isBackground(img.pixel(2, 2)));
        QVERIFY(isBackground(img.pixel(img.width() - 3, img.height() - 3)));
    }

    void clickPinsTheVertexUnderTheCursor()
    {
        const auto frame = m_view->controller()->currentFrame();
        QVERIFY(frame);
        // A vertex on the pedestal top, off-centre: it faces the top camera.
        int target = -1;
        double best = 1e9;
        for (int i = 0; i < frame->x.rows(); ++i) {
            const double d = (Eigen::Vector3d(frame->x.row(i)) - Eigen::Vector3d(0.031, -0.022, 0.0)).norm();
            if (d < best) {
                best = d;
                target = i;
            }
        }
        QVERIFY(target >= 0);
        QVERIFY(!m_view->controller()->isPinned(target));
        QQuickWidget* qw = m_view->quickWidget();
        const QSize s = qw->size();
        const Eigen::Vector3d p = frame->x.row(target);
        const QPointF q = m_view->controller()->projectToView(QVector3D(float(p.x()), float(p.y()), float(p.z())),
                                                              s.width(), s.height());
        QSignalSpy pinned(m_view->controller(), &DrapeController::pinnedChanged);
        QTest::mouseClick(qw, Qt::LeftButton, Qt::NoModifier, q.toPoint());
        QTRY_VERIFY_WITH_TIMEOUT(pinned.count() > 0, 5000);
        QCOMPARE(m_view->controller()->pinnedVertices(), QList<int>{target});
        QSignalSpy frames(m_view->controller(), &DrapeController::frameApplied);
        QVERIFY(frames.wait(10000));
        QVERIFY(m_view->controller()->simulatedPinnedVertices().contains(target));

        // The pin marker is drawn: a yellow dot at the vertex.
        QTest::qWait(200);
        const QImage img = grab();
        const QPoint at = toImage(img, p);
        const QRgb c = img.pixel(at);
        QVERIFY2(qRed(c) > 180 && qGreen(c) > 150 && qBlue(c) < 100, qPrintable(QColor(c).name()));

        // Clicking it again unpins it; clicking the background changes nothing.
        QTest::mouseClick(qw, Qt::LeftButton, Qt::NoModifier, q.toPoint());
        QTRY_VERIFY_WITH_TIMEOUT(m_view->controller()->pinnedVertices().isEmpty(), 5000);
        QTest::mouseClick(qw, Qt::LeftButton, Qt::NoModifier, QPoint(3, 3));
        QTest::qWait(100);
        QVERIFY(m_view->controller()->pinnedVertices().isEmpty());
    }

    void dragOrbitsAndWheelZooms()
    {
        QQuickWidget* qw = m_view->quickWidget();
        // From the top station a horizontal drag turns the view about the vertical
        // axis (the camera stays above the pedestal), a vertical drag tilts it.
        const QQuaternion rotBefore = m_view->controller()->cameraRotation();
        const QVector3D before = m_view->controller()->cameraPosition();
        const QPoint c(qw->width() / 2, qw->height() / 2);
        QTest::mousePress(qw, Qt::LeftButton, Qt::NoModifier, c);
        for (int k = 1; k <= 10; ++k) QTest::mouseMove(qw, c + QPoint(6 * k, 0));
        QTest::mouseRelease(qw, Qt::LeftButton, Qt::NoModifier, c + QPoint(60, 0));
        QTRY_COMPARE_WITH_TIMEOUT(m_view->viewPreset(), Drape::Free, 5000);
        QVERIFY(std::abs(QQuaternion::dotProduct(m_view->controller()->cameraRotation(), rotBefore)) < 0.999);
        QVERIFY((m_view->controller()->cameraPosition() - before).length() < 1e-5);
        QTest::mousePress(qw, Qt::LeftButton, Qt::NoModifier, c);
        for (int k = 1; k <= 10; ++k) QTest::mouseMove(qw, c + QPoint(0, -6 * k)); // up: lower the camera
        QTest::mouseRelease(qw, Qt::LeftButton, Qt::NoModifier, c + QPoint(0, -60));
        QTRY_VERIFY_WITH_TIMEOUT((m_view->controller()->cameraPosition() - before).length() > 1e-2, 5000);
        QVERIFY(m_view->controller()->pinnedVertices().isEmpty()); // a drag is not a click
        const double d0 = m_view->controller()->camera().distance;
        m_view->controller()->zoom(120);
        QVERIFY(m_view->controller()->camera().distance < d0);
        // Back to the lab's side station.
        m_view->setViewPreset(Drape::Side);
        const Eigen::Vector3d pos = m_view->controller()->camera().position();
        QVERIFY((pos - Eigen::Vector3d(0, -1, 0)).norm() < 1e-9);
    }
};

QTEST_MAIN(TstDrapeRender)
#include "tst_drape_render.moc"
