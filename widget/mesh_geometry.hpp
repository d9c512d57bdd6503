#pragma once
// A triangle mesh as Qt Quick 3D geometry: smooth per-vertex normals and texture
// coordinates, uploaded from the frame packer's buffers on the GUI thread.
#include "widget/drape_widget_export.hpp"
#include <QtQml/qqmlregistration.h>
#include "widget/frame_packer.hpp"

#include <QQuick3DGeometry>

namespace drape::widget {

class DRAPE_WIDGET_EXPORT MeshGeometry : public QQuick3DGeometry {
    Q_OBJECT
    QML_ELEMENT
    QML_UNCREATABLE("use Scene.items")
    Q_PROPERTY(int vertexCount READ vertexCount NOTIFY meshChanged)
    Q_PROPERTY(int triangleCount READ triangleCount NOTIFY meshChanged)
public:
    explicit MeshGeometry(QQuick3DObject* parent = nullptr);

    int vertexCount() const { return m_vertexCount; }
    int triangleCount() const { return m_triangleCount; }

    /// New triangles. Draws nothing until the first setVertices of this topology.
    void setTopology(const PackedTopology& topology);
    /// New positions and normals; false (and nothing changes) when the vertex
    /// count is not the topology's.
    bool setVertices(const PackedVertices& vertices);

signals:
    void meshChanged();

private:
    int m_vertexCount = 0;
    int m_triangleCount = 0;
};

} // namespace drape::widget
