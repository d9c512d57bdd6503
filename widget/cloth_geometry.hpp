#pragma once
// The cloth as Qt Quick 3D geometry: triangles with smooth per-vertex normals and
// texture coordinates, updated from the worker's frames on the GUI thread.
#include "widget/drape_frame.hpp"

#include <QQuick3DGeometry>

namespace drape::widget {

class ClothGeometry : public QQuick3DGeometry {
    Q_OBJECT
    Q_PROPERTY(int vertexCount READ vertexCount NOTIFY meshChanged)
    Q_PROPERTY(int triangleCount READ triangleCount NOTIFY meshChanged)
public:
    explicit ClothGeometry(QQuick3DObject* parent = nullptr);

    int vertexCount() const { return m_vertexCount; }
    int triangleCount() const { return m_triangleCount; }

    /// New topology (after a rebuild). Clears the vertex data until the next frame.
    void setMesh(const DrapeMeshPtr& mesh);
    /// New positions and normals; ignored when the frame belongs to another mesh.
    /// Returns true when the frame was taken.
    bool setFrame(const DrapeFramePtr& frame);

signals:
    void meshChanged();

private:
    int m_generation = -1;
    int m_vertexCount = 0;
    int m_triangleCount = 0;
};

} // namespace drape::widget
