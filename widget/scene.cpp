#include "widget/scene.hpp"

#include "widget/world_frame.hpp"

#include <cmath>

namespace drape::widget {

// ---- SceneItemList ------------------------------------------------------------------

int SceneItemList::rowCount(const QModelIndex& parent) const
{
    return parent.isValid() ? 0 : int(m_items.size());
}

QVariant SceneItemList::data(const QModelIndex& index, int role) const
{
    if (role != Qt::UserRole || !index.isValid() || index.row() >= int(m_items.size())) return {};
    return QVariant::fromValue(static_cast<QObject*>(m_items[std::size_t(index.row())]));
}

QHash<int, QByteArray> SceneItemList::roleNames() const
{
    return {{Qt::UserRole, "sceneItem"}};
}

SceneItem* SceneItemList::find(const QString& name) const
{
    for (SceneItem* i : m_items)
        if (i->name() == name) return i;
    return nullptr;
}

void SceneItemList::put(SceneItem* item)
{
    remove(item->name());
    beginInsertRows({}, int(m_items.size()), int(m_items.size()));
    m_items.push_back(item);
    endInsertRows();
}

void SceneItemList::remove(const QString& name)
{
    for (std::size_t k = 0; k < m_items.size(); ++k)
        if (m_items[k]->name() == name) {
            beginRemoveRows({}, int(k), int(k));
            SceneItem* old = m_items[k];
            m_items.erase(m_items.begin() + std::ptrdiff_t(k));
            endRemoveRows();
            old->deleteLater(); // the view may still hold its geometry until it drops the delegate
            return;
        }
}

void SceneItemList::clear()
{
    if (m_items.empty()) return;
    beginResetModel();
    std::vector<SceneItem*> gone;
    gone.swap(m_items);
    endResetModel();
    for (SceneItem* i : gone) i->deleteLater();
}

// ---- Scene --------------------------------------------------------------------------

Scene::Scene(QObject* parent) : QObject(parent), m_items(new SceneItemList(this)) {}

SceneMesh* Scene::addMesh(const QString& name, const cloth::Positions& X, const cloth::Triangles& F,
                          std::vector<float> texcoord)
{
    auto* m = new SceneMesh(name, this);
    m->setTopology(F, int(X.rows()), std::move(texcoord));
    m->updatePositions(X);
    return insert(m);
}

SceneMesh* Scene::addMesh(const QString& name)
{
    return insert(new SceneMesh(name, this));
}

SceneItem* Scene::addShape(const QString& name, const QString& primitive, const QVector3D& position,
                           const QVector3D& scale, const QQuaternion& rotation)
{
    auto* s = new SceneItem(name, nullptr, primitive, this);
    s->setTransform(position, scale, rotation);
    return insert(s);
}

SceneItem* Scene::addGeometry(const QString& name, QQuick3DGeometry* geometry)
{
    return insert(new SceneItem(name, geometry, QString(), this));
}

SceneItem* Scene::item(const QString& name) const
{
    return m_items->find(name);
}

SceneMesh* Scene::mesh(const QString& name) const
{
    return qobject_cast<SceneMesh*>(item(name));
}

void Scene::removeItem(const QString& name)
{
    m_items->remove(name);
}

void Scene::clear()
{
    m_items->clear();
}

void Scene::setMarkers(const std::vector<Eigen::Vector3d>& worldPoints, double radius, const QColor& color)
{
    QVariantList list;
    for (const Eigen::Vector3d& p : worldPoints) list.push_back(toScene(p.x(), p.y(), p.z()));
    const float k = float(radius / 50); // #Sphere: radius 50 units
    const QVector3D scale(k, k, k);
    if (list == m_markers && scale == m_markerScale && color == m_markerColor) return;
    m_markers = list;
    m_markerScale = scale;
    m_markerColor = color;
    emit markersChanged();
}

QPointF Scene::projectToView(const Eigen::Vector3d& world, double w, double h) const
{
    double px = 0, py = 0;
    if (!m_camera.project(world, w, h, px, py)) return {std::nan(""), std::nan("")};
    return {px, py};
}

void Scene::setBackgroundColor(const QColor& c)
{
    if (c == m_background) return;
    m_background = c;
    emit appearanceChanged();
}

void Scene::setAntialiasing(bool on)
{
    if (on == m_antialiasing) return;
    m_antialiasing = on;
    emit appearanceChanged();
}

void Scene::setTitle(const QString& t)
{
    if (t == m_title) return;
    m_title = t;
    emit textChanged();
}

void Scene::setStatusText(const QString& t)
{
    if (t == m_status) return;
    m_status = t;
    emit textChanged();
}

void Scene::orbit(double dxPixels, double dyPixels)
{
    m_camera.orbit(-dxPixels * 0.01, dyPixels * 0.01); // [rad per pixel]
    emit cameraChanged();
    emit cameraMoved();
}

void Scene::pan(double dxPixels, double dyPixels, double viewHeight)
{
    if (!(viewHeight > 0)) return;
    m_camera.pan(dxPixels / viewHeight, dyPixels / viewHeight);
    emit cameraChanged();
    emit cameraMoved();
}

void Scene::zoom(double wheelDelta)
{
    m_camera.zoom(std::pow(0.999, wheelDelta)); // one notch (120) = 11 % closer
    emit cameraChanged();
}

} // namespace drape::widget
