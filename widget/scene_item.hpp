#pragma once
// What a Scene draws. A SceneItem is one Qt Quick 3D model: a geometry object
// (outline lines, the lab's floor boards) or a built-in primitive ("#Cylinder",
// "#Sphere", "#Rectangle": 100 units across, placed by position, scale and
// rotation in scene coordinates), with one PrincipledMaterial. A SceneMesh is an
// item whose triangle mesh the host gives in world coordinates (z up, metres)
// and whose positions it updates: a body, a table top, a cloth.
#include "widget/drape_widget_export.hpp"
#include <QtQml/qqmlregistration.h>
#include "widget/frame_packer.hpp"
#include "widget/mesh_geometry.hpp"

#include <QColor>
#include <QImage>
#include <QObject>
#include <QQuaternion>
#include <QQuick3DGeometry>
#include <QQuick3DTextureData>
#include <QString>
#include <QVector3D>

#include <vector>

namespace drape::widget {

class DRAPE_WIDGET_EXPORT SceneItem : public QObject {
    Q_OBJECT
    QML_ELEMENT
    QML_UNCREATABLE("use Scene.items")
    Q_PROPERTY(QString name READ name CONSTANT)
    Q_PROPERTY(QQuick3DGeometry* geometry READ geometry CONSTANT)
    Q_PROPERTY(QString source READ source CONSTANT)
    Q_PROPERTY(QVector3D position READ position NOTIFY changed)
    Q_PROPERTY(QVector3D scale READ scale NOTIFY changed)
    Q_PROPERTY(QQuaternion rotation READ rotation NOTIFY changed)
    Q_PROPERTY(bool visible READ isVisible NOTIFY changed)
    Q_PROPERTY(QColor color READ color NOTIFY changed)
    Q_PROPERTY(bool lit READ lit NOTIFY changed)               ///< false: flat colour (lines, markers)
    Q_PROPERTY(bool doubleSided READ doubleSided NOTIFY changed) ///< both faces drawn and lit
    Q_PROPERTY(double roughness READ roughness NOTIFY changed)
    Q_PROPERTY(double specularAmount READ specularAmount NOTIFY changed)
    Q_PROPERTY(bool textured READ textured NOTIFY changed)
public:
    /// `geometry` (owned from now on) or a built-in primitive `source`.
    SceneItem(const QString& name, QQuick3DGeometry* geometry, const QString& source, QObject* parent = nullptr);

    QString name() const { return m_name; }
    QQuick3DGeometry* geometry() const { return m_geometry; }
    QString source() const { return m_source; }
    QVector3D position() const { return m_position; }
    QVector3D scale() const { return m_scale; }
    QQuaternion rotation() const { return m_rotation; }
    bool isVisible() const { return m_visible; }
    QColor color() const { return m_color; }
    bool lit() const { return m_lit; }
    bool doubleSided() const { return m_doubleSided; }
    double roughness() const { return m_roughness; }
    double specularAmount() const { return m_specular; }
    bool textured() const { return m_textured; }
    /// The texture as uploaded (RGBA8, rows bottom-up) and a number that grows with every new image.
    const QImage& textureImage() const { return m_textureImage; }
    int textureRevision() const { return m_textureRevision; }

    /// Scene coordinates (y up) [m]; a primitive's scale is per 100 units.
    void setTransform(const QVector3D& position, const QVector3D& scale, const QQuaternion& rotation = {});
    void setVisible(bool on);
    void setColor(const QColor& c);
    /// Material: lighting on/off, both faces, roughness and specular amount [0, 1].
    void setMaterial(bool lit, bool doubleSided, double roughness, double specularAmount);
    /// Maps `image` over the texture coordinates (v up: image rows are mirrored so
    /// the image is upright seen along -z); the colour then is white.
    void setTextureImage(const QImage& image);
    void clearTexture();

signals:
    void changed();

private:
    QString m_name;
    QQuick3DGeometry* m_geometry = nullptr;
    QString m_source;
    QVector3D m_position;
    QVector3D m_scale{1, 1, 1};
    QQuaternion m_rotation;
    bool m_visible = true;
    QColor m_color{0x80, 0x80, 0x80};
    bool m_lit = true;
    bool m_doubleSided = true;
    double m_roughness = 0.9;
    double m_specular = 0.1;
    bool m_textured = false;
    QImage m_textureImage;
    int m_textureRevision = 0;
};

/// A SceneItem's texture image as Qt Quick 3D texture data. Each view's delegate
/// makes its own (qml/SceneView.qml: Texture { textureData: SceneTexture { item: ... } }),
/// so the data lives exactly as long as the Texture using it: Qt 6.4's Texture
/// leaves a connection behind on texture data that outlives it.
class DRAPE_WIDGET_EXPORT SceneTextureData : public QQuick3DTextureData {
    Q_OBJECT
    QML_NAMED_ELEMENT(SceneTexture)
    Q_PROPERTY(drape::widget::SceneItem* item READ item WRITE setItem NOTIFY itemChanged)
public:
    explicit SceneTextureData(QQuick3DObject* parent = nullptr);
    SceneItem* item() const { return m_item; }
    void setItem(SceneItem* item);

signals:
    void itemChanged();

private:
    void upload();
    SceneItem* m_item = nullptr;
    int m_revision = -1;
    QMetaObject::Connection m_connection;
};

class DRAPE_WIDGET_EXPORT SceneMesh : public SceneItem {
    Q_OBJECT
    QML_ANONYMOUS
public:
    explicit SceneMesh(const QString& name, QObject* parent = nullptr);

    MeshGeometry* meshGeometry() const { return m_mesh; }
    int vertexCount() const { return m_mesh->vertexCount(); }
    int triangleCount() const { return m_mesh->triangleCount(); }
    const cloth::Triangles& triangles() const { return m_F; }

    /// New triangles for `vertexCount` vertices and their texture coordinates
    /// (2 per vertex, or empty). Nothing is drawn until the first positions.
    void setTopology(const cloth::Triangles& F, int vertexCount, std::vector<float> texcoord = {});
    /// New world positions [m] (n x 3, the topology's n), packed here.
    bool updatePositions(const cloth::Positions& X);
    /// New positions packed elsewhere (packVertices on a worker thread, with this
    /// mesh's triangles and texture coordinates). False when the count differs.
    bool setVertices(const PackedVertices& vertices);

private:
    MeshGeometry* m_mesh = nullptr;
    cloth::Triangles m_F;
    std::vector<float> m_texcoord;
};

} // namespace drape::widget
