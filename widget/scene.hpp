#pragma once
// Scene: a small polyscope-style viewer scene that a host fills - register a
// mesh (a body, a table), then update its positions (a cloth) - and that one
// QML file draws (qml/SceneView.qml, shown in a QWidget by SceneWidget). It
// holds the orbit camera, the items, pin-style markers and two lines of text;
// the mouse in the view orbits, pans, zooms and reports clicks.
//
// The drapemeter controller (DrapeController) is one client, the fitting demo
// another. Positions are in Drapekit's world frame (z up, metres); the items'
// transforms are in the scene frame (y up, see world_frame.hpp). GUI thread only;
// pack frames on a worker with packVertices and hand them to SceneMesh::setVertices.
#include "widget/drape_widget_export.hpp"
#include <QtQml/qqmlregistration.h>
#include "widget/orbit_camera.hpp"
#include "widget/scene_item.hpp"

#include <QAbstractListModel>
#include <QColor>
#include <QObject>
#include <QPointF>
#include <QQuaternion>
#include <QVariantList>
#include <QVector3D>

#include <vector>

namespace drape::widget {

/// The scene's items as a list model (one role, "sceneItem"): the view adds and
/// removes the delegates of the items that come and go and keeps the others.
class DRAPE_WIDGET_EXPORT SceneItemList : public QAbstractListModel {
    Q_OBJECT
public:
    using QAbstractListModel::QAbstractListModel;
    int rowCount(const QModelIndex& parent = {}) const override;
    QVariant data(const QModelIndex& index, int role) const override;
    QHash<int, QByteArray> roleNames() const override;

    SceneItem* find(const QString& name) const;
    /// Adds `item`; an item of the same name goes (deleted later).
    void put(SceneItem* item);
    void remove(const QString& name);
    void clear();

private:
    std::vector<SceneItem*> m_items;
};

class DRAPE_WIDGET_EXPORT Scene : public QObject {
    Q_OBJECT
    QML_ELEMENT
    QML_UNCREATABLE("a host fills a Scene from C++")
    Q_PROPERTY(QAbstractListModel* items READ items CONSTANT)
    Q_PROPERTY(QVariantList markers READ markers NOTIFY markersChanged) ///< scene positions
    Q_PROPERTY(QVector3D markerScale READ markerScale NOTIFY markersChanged)
    Q_PROPERTY(QColor markerColor READ markerColor NOTIFY markersChanged)
    Q_PROPERTY(QColor backgroundColor READ backgroundColor WRITE setBackgroundColor NOTIFY appearanceChanged)
    Q_PROPERTY(bool antialiasing READ antialiasing WRITE setAntialiasing NOTIFY appearanceChanged)
    Q_PROPERTY(QString title READ title WRITE setTitle NOTIFY textChanged)           ///< top-left, large
    Q_PROPERTY(QString statusText READ statusText WRITE setStatusText NOTIFY textChanged) ///< bottom-left, small
    Q_PROPERTY(QVector3D cameraPosition READ cameraPosition NOTIFY cameraChanged)
    Q_PROPERTY(QQuaternion cameraRotation READ cameraRotation NOTIFY cameraChanged)
    Q_PROPERTY(double fieldOfView READ fieldOfView NOTIFY cameraChanged) ///< vertical [deg]
public:
    explicit Scene(QObject* parent = nullptr);

    // ---- registering things to draw (polyscope's registerSurfaceMesh & co) -----
    /// A triangle mesh at world positions X [m] (n x 3) with triangles F; texture
    /// coordinates 2 per vertex or empty. Replaces an item of the same name.
    SceneMesh* addMesh(const QString& name, const cloth::Positions& X, const cloth::Triangles& F,
                       std::vector<float> texcoord = {});
    /// A mesh whose topology and positions come later (SceneMesh::setTopology).
    SceneMesh* addMesh(const QString& name);
    /// A built-in primitive ("#Cylinder", "#Sphere", "#Rectangle") placed in scene coordinates.
    SceneItem* addShape(const QString& name, const QString& primitive, const QVector3D& position,
                        const QVector3D& scale, const QQuaternion& rotation = {});
    /// Any Qt Quick 3D geometry (lines, the floor boards); the scene owns it.
    SceneItem* addGeometry(const QString& name, QQuick3DGeometry* geometry);
    SceneItem* item(const QString& name) const;
    SceneMesh* mesh(const QString& name) const;
    void removeItem(const QString& name);
    void clear();

    /// Small unlit spheres at world points [m] (e.g. pinned vertices); radius [m].
    void setMarkers(const std::vector<Eigen::Vector3d>& worldPoints, double radius, const QColor& color);

    // ---- view ------------------------------------------------------------------
    OrbitCamera& camera() { return m_camera; }
    const OrbitCamera& camera() const { return m_camera; }
    /// Call after changing camera() directly: the view follows.
    void cameraUpdated() { emit cameraChanged(); }
    /// World point [m] -> point of a w x h view (NaN when behind the camera).
    QPointF projectToView(const Eigen::Vector3d& world, double w, double h) const;

    QAbstractListModel* items() const { return m_items; }
    QVariantList markers() const { return m_markers; }
    QVector3D markerScale() const { return m_markerScale; }
    QColor markerColor() const { return m_markerColor; }
    QColor backgroundColor() const { return m_background; }
    void setBackgroundColor(const QColor& c);
    bool antialiasing() const { return m_antialiasing; }
    void setAntialiasing(bool on);
    QString title() const { return m_title; }
    void setTitle(const QString& t);
    QString statusText() const { return m_status; }
    void setStatusText(const QString& t);
    QVector3D cameraPosition() const { return m_camera.scenePosition(); }
    QQuaternion cameraRotation() const { return m_camera.sceneRotation(); }
    double fieldOfView() const { return m_camera.fovYDegrees(); }

    // ---- mouse (called by the QML view) ------------------------------------------
    Q_INVOKABLE void orbit(double dxPixels, double dyPixels);
    Q_INVOKABLE void pan(double dxPixels, double dyPixels, double viewHeight);
    Q_INVOKABLE void zoom(double wheelDelta);
    /// A click without a drag at view point (x, y) of a w x h view.
    Q_INVOKABLE void click(double x, double y, double w, double h) { emit clicked(x, y, w, h); }

signals:
    void markersChanged();
    void appearanceChanged();
    void textChanged();
    void cameraChanged();
    /// The user orbited or panned (the camera left any preset station).
    void cameraMoved();
    void clicked(double x, double y, double w, double h);

private:
    template <class T>
    T* insert(T* item)
    {
        m_items->put(item);
        return item;
    }

    SceneItemList* m_items = nullptr;
    OrbitCamera m_camera;
    QVariantList m_markers;
    QVector3D m_markerScale;
    QColor m_markerColor{0xff, 0xd0, 0x00};
    QColor m_background{0x2b, 0x2f, 0x36};
    bool m_antialiasing = false;
    QString m_title, m_status;
};

} // namespace drape::widget
