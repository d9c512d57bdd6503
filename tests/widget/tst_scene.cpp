// The scene a host fills: the frame packer's buffers (positions in the scene
// frame, unit smooth normals, texture coordinates, bounds), registering,
// replacing and removing items, markers and the camera's signals, RestJob
// bringing a system to rest while it updates a mesh, and a SceneWidget drawing
// a registered mesh where the camera projects it.
#include "widget/frame_packer.hpp"
#include "widget/rest_job.hpp"
#include "widget/scene.hpp"
#include "widget/scene_widget.hpp"

#include "engine/cloth/drape.hpp"

#include <QSignalSpy>
#include <QTest>

#include <cmath>

using namespace drape;
using widget::Scene;

namespace {

/// Two triangles of a w x w square centred at the origin in the plane z [m], counter-clockwise from +z.
void square(double w, double z, cloth::Positions& X, cloth::Triangles& F)
{
    X.resize(4, 3);
    X << -w / 2, -w / 2, z, w / 2, -w / 2, z, w / 2, w / 2, z, -w / 2, w / 2, z;
    F.resize(2, 3);
    F << 0, 1, 2, 0, 2, 3;
}

const float* floats(const widget::PackedVertices& v)
{
    return reinterpret_cast<const float*>(v.data.constData());
}

} // namespace

class TstScene : public QObject {
    Q_OBJECT

private slots:
    void packerWritesSceneFrameNormalsAndTexcoords()
    {
        cloth::Positions X;
        cloth::Triangles F;
        square(0.2, 0.05, X, F);
        const std::vector<float> tex{0, 0, 1, 0, 1, 1, 0, 1};
        const widget::PackedVertices v = widget::packVertices(X, F, tex);
        QCOMPARE(v.vertexCount, 4);
        QCOMPARE(v.data.size(), qsizetype(4 * widget::kFloatsPerVertex * sizeof(float)));
        const float* f = floats(v);
        for (int i = 0; i < 4; ++i) {
            const float* o = f + i * widget::kFloatsPerVertex;
            // scene = (x, z, -y)
            QCOMPARE(o[0], float(X(i, 0)));
            QCOMPARE(o[1], float(X(i, 2)));
            QCOMPARE(o[2], float(-X(i, 1)));
            // A flat sheet facing +z has the scene's +y as normal, unit length.
            QVERIFY(std::abs(o[3]) < 1e-6f && std::abs(o[4] - 1.0f) < 1e-6f && std::abs(o[5]) < 1e-6f);
            QCOMPARE(o[6], tex[std::size_t(2 * i)]);
            QCOMPARE(o[7], tex[std::size_t(2 * i + 1)]);
        }
        QCOMPARE(v.boundsMin, QVector3D(-0.1f, 0.05f, -0.1f));
        QCOMPARE(v.boundsMax, QVector3D(0.1f, 0.05f, 0.1f));
        // Without texture coordinates: zeros.
        const widget::PackedVertices plain = widget::packVertices(X, F, {});
        QCOMPARE(floats(plain)[6], 0.0f);
        QCOMPARE(floats(plain)[2 * widget::kFloatsPerVertex + 7], 0.0f);

        const widget::PackedTopology t = widget::packTopology(F, 4);
        QCOMPARE(t.triangleCount, 2);
        const auto* idx = reinterpret_cast<const quint32*>(t.indices.constData());
        QCOMPARE(idx[3], 0u);
        QCOMPARE(idx[5], 3u);
    }

    void texcoordsKeepTheMaterialsAspect()
    {
        Eigen::MatrixX2d uv(3, 2);
        uv << 1.0, 2.0, 1.4, 2.0, 1.0, 2.2; // 0.4 m x 0.2 m
        const std::vector<float> t = widget::texcoordsFromMaterial(uv, 3);
        QCOMPARE(t, (std::vector<float>{0.0f, 0.0f, 1.0f, 0.0f, 0.0f, 0.5f}));
        QCOMPARE(widget::texcoordsFromMaterial(uv, 4), std::vector<float>(8, 0.0f)); // wrong size: zeros
    }

    void itemsComeAndGo()
    {
        Scene scene;
        cloth::Positions X;
        cloth::Triangles F;
        square(0.3, 0.0, X, F);
        QAbstractListModel* model = scene.items();
        widget::SceneMesh* body = scene.addMesh("body", X, F);
        QCOMPARE(body->vertexCount(), 4);
        QCOMPARE(body->triangleCount(), 2);
        QCOMPARE(scene.mesh("body"), body);
        QVERIFY(!body->updatePositions(cloth::Positions::Zero(3, 3))); // another vertex count
        QVERIFY(body->updatePositions(X));
        scene.addShape("table", "#Cylinder", QVector3D(0, 0.4f, 0), QVector3D(1, 1, 1));
        QCOMPARE(model->rowCount(), 2);
        // The list model hands the view its items.
        QCOMPARE(model->data(model->index(1, 0), Qt::UserRole).value<QObject*>(), scene.item("table"));
        // The same name replaces; removing takes it out.
        QPointer<widget::SceneItem> old = scene.item("table");
        scene.addShape("table", "#Sphere", QVector3D(), QVector3D(1, 1, 1));
        QCOMPARE(model->rowCount(), 2);
        QCOMPARE(scene.item("table")->source(), QStringLiteral("#Sphere"));
        scene.removeItem("body");
        QCOMPARE(model->rowCount(), 1);
        QVERIFY(!scene.item("body"));
        QCoreApplication::sendPostedEvents(nullptr, QEvent::DeferredDelete);
        QVERIFY(!old); // replaced items are deleted once the view had a chance to drop them
        scene.clear();
        QCOMPARE(model->rowCount(), 0);

        // Markers: scene positions, a #Sphere scaled to the radius.
        scene.setMarkers({Eigen::Vector3d(0.1, 0.2, 0.3)}, 0.004, Qt::yellow);
        QCOMPARE(scene.markers().size(), 1);
        QCOMPARE(scene.markers().at(0).value<QVector3D>(), QVector3D(0.1f, 0.3f, -0.2f));
        QCOMPARE(scene.markerScale().x(), 0.004f / 50);
    }

    void mouseMovesTheCamera()
    {
        Scene scene;
        QSignalSpy camera(&scene, &Scene::cameraChanged);
        QSignalSpy moved(&scene, &Scene::cameraMoved);
        QSignalSpy clicked(&scene, &Scene::clicked);
        const double d0 = scene.camera().distance;
        scene.zoom(120);
        QVERIFY(scene.camera().distance < d0);
        QCOMPARE(moved.count(), 0); // zooming keeps a preset station's direction
        scene.orbit(10, 0);
        scene.pan(5, 5, 100);
        QCOMPARE(moved.count(), 2);
        QCOMPARE(camera.count(), 3);
        scene.click(1, 2, 3, 4);
        QCOMPARE(clicked.count(), 1);
    }

    void restJobShowsTheDrapeAsItGoes()
    {
        Scene scene;
        widget::SceneMesh* cloth = scene.addMesh("cloth");
        cloth::DrapeSetup su;
        su.grid = 12;
        auto sys = cloth::make_drape_system(cloth::FabricParams(), su);
        const cloth::Positions start = sys->x;
        widget::RestJob job;
        QSignalSpy progress(&job, &widget::RestJob::progress);
        QSignalSpy finished(&job, &widget::RestJob::finished);
        cloth::RestOptions opt;
        opt.residual = 1e-4;
        QVERIFY(job.start("drape", *sys, opt, cloth));
        QVERIFY(job.running());
        QVERIFY(!job.start("again", *sys, opt, cloth)); // one at a time
        QCOMPARE(cloth->vertexCount(), sys->vertex_count()); // the topology is the system's at once
        QVERIFY(finished.wait(120000));
        QVERIFY2(finished.at(0).at(0).toBool(), qPrintable(finished.at(0).at(1).toString()));
        QVERIFY(job.status().converged());
        QVERIFY(finished.at(0).at(1).toString().contains("Newton iterations"));
        QVERIFY(progress.count() > 0);
        for (const QList<QVariant>& p : progress) QVERIFY(p.at(0).toDouble() <= 1.0);
        QVERIFY((sys->x - start).norm() > 1e-3); // it draped
    }

    void widgetDrawsARegisteredMesh()
    {
        widget::SceneWidget view;
        view.resize(320, 240);
        Scene* scene = view.scene();
        scene->setBackgroundColor(QColor(40, 90, 60));
        cloth::Positions X;
        cloth::Triangles F;
        square(0.3, 0.0, X, F);
        widget::SceneMesh* m = scene->addMesh("sheet", X, F);
        m->setColor(QColor(230, 40, 40));
        m->setMaterial(false, true, 0.9, 0.1); // unlit: the colour as given
        scene->camera().setPreset(widget::OrbitCamera::Preset::Top);
        scene->cameraUpdated();
        view.show();
        QVERIFY(QTest::qWaitForWindowExposed(&view));
        QTest::qWait(100);
        const QImage img = view.grabFrame();
        QVERIFY(!img.isNull());
        const QPointF c = scene->projectToView(Eigen::Vector3d(0.05, 0.05, 0), 320, 240);
        const QRgb inside = img.pixel(int(c.x() * img.width() / 320), int(c.y() * img.height() / 240));
        QVERIFY2(qRed(inside) > 200 && qGreen(inside) < 80, qPrintable(QColor(inside).name()));
        const QRgb corner = img.pixel(2, 2);
        QVERIFY2(qGreen(corner) > qRed(corner), qPrintable(QColor(corner).name()));
        // Removing it leaves the background.
        scene->removeItem("sheet");
        QTest::qWait(100);
        const QRgb after = view.grabFrame().pixel(int(c.x() * img.width() / 320), int(c.y() * img.height() / 240));
        QVERIFY2(qGreen(after) > qRed(after), qPrintable(QColor(after).name()));
    }
};

QTEST_MAIN(TstScene)
#include "tst_scene.moc"
