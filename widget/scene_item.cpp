#include "widget/scene_item.hpp"

namespace drape::widget {

SceneItem::SceneItem(const QString& name, QQuick3DGeometry* geometry, const QString& source, QObject* parent)
    : QObject(parent), m_name(name), m_geometry(geometry), m_source(source)
{
    if (m_geometry) m_geometry->QObject::setParent(this);
}

void SceneItem::setTransform(const QVector3D& position, const QVector3D& scale, const QQuaternion& rotation)
{
    if (position == m_position && scale == m_scale && rotation == m_rotation) return;
    m_position = position;
    m_scale = scale;
    m_rotation = rotation;
    emit changed();
}

void SceneItem::setVisible(bool on)
{
    if (on == m_visible) return;
    m_visible = on;
    emit changed();
}

void SceneItem::setColor(const QColor& c)
{
    if (c == m_color) return;
    m_color = c;
    emit changed();
}

void SceneItem::setMaterial(bool lit, bool doubleSided, double roughness, double specularAmount)
{
    m_lit = lit;
    m_doubleSided = doubleSided;
    m_roughness = roughness;
    m_specular = specularAmount;
    emit changed();
}

void SceneItem::setTextureImage(const QImage& image)
{
    // Texture coordinate v grows upwards while image rows run downwards: mirror
    // so the image is upright.
    m_textureImage = image.convertToFormat(QImage::Format_RGBA8888).mirrored(false, true);
    ++m_textureRevision;
    m_textured = true;
    emit changed();
}

void SceneItem::clearTexture()
{
    if (!m_textured) return;
    m_textured = false;
    emit changed();
}

SceneTextureData::SceneTextureData(QQuick3DObject* parent) : QQuick3DTextureData(parent)
{
    setFormat(QQuick3DTextureData::RGBA8);
    setHasTransparency(false);
}

void SceneTextureData::setItem(SceneItem* item)
{
    if (item == m_item) return;
    disconnect(m_connection);
    m_item = item;
    m_revision = -1;
    if (m_item) m_connection = connect(m_item, &SceneItem::changed, this, &SceneTextureData::upload);
    upload();
    emit itemChanged();
}

void SceneTextureData::upload()
{
    if (!m_item || m_item->textureRevision() == m_revision) return;
    m_revision = m_item->textureRevision();
    const QImage& img = m_item->textureImage();
    setSize(img.size());
    setTextureData(QByteArray(reinterpret_cast<const char*>(img.constBits()), img.sizeInBytes()));
}

SceneMesh::SceneMesh(const QString& name, QObject* parent) : SceneItem(name, new MeshGeometry(), QString(), parent)
{
    m_mesh = static_cast<MeshGeometry*>(geometry());
}

void SceneMesh::setTopology(const cloth::Triangles& F, int vertexCount, std::vector<float> texcoord)
{
    m_F = F;
    m_texcoord = std::move(texcoord);
    m_mesh->setTopology(packTopology(F, vertexCount));
}

bool SceneMesh::updatePositions(const cloth::Positions& X)
{
    if (X.rows() != m_mesh->vertexCount()) return false;
    return m_mesh->setVertices(packVertices(X, m_F, m_texcoord));
}

bool SceneMesh::setVertices(const PackedVertices& vertices)
{
    return m_mesh->setVertices(vertices);
}

} // namespace drape::widget
