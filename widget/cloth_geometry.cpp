#include "widget/cloth_geometry.hpp"

namespace drape::widget {

ClothGeometry::ClothGeometry(QQuick3DObject* parent) : QQuick3DGeometry(parent)
{
    setPrimitiveType(PrimitiveType::Triangles);
    setStride(kFloatsPerVertex * int(sizeof(float)));
    addAttribute(Attribute::PositionSemantic, 0, Attribute::F32Type);
    addAttribute(Attribute::NormalSemantic, 3 * sizeof(float), Attribute::F32Type);
    addAttribute(Attribute::TexCoord0Semantic, 6 * sizeof(float), Attribute::F32Type);
    addAttribute(Attribute::IndexSemantic, 0, Attribute::U32Type);
}

void ClothGeometry::setMesh(const DrapeMeshPtr& mesh)
{
    if (!mesh) return;
    if (mesh->generation == m_generation) return;
    m_generation = mesh->generation;
    m_vertexCount = mesh->vertexCount;
    m_triangleCount = int(mesh->F.rows());
    setIndexData(mesh->indexData);
    // Keep the buffers consistent: no vertices until the first frame of this mesh.
    setVertexData(QByteArray());
    emit meshChanged();
    update();
}

bool ClothGeometry::setFrame(const DrapeFramePtr& frame)
{
    if (!frame || frame->generation != m_generation) return false;
    if (frame->vertexData.size() != qsizetype(m_vertexCount) * kFloatsPerVertex * qsizetype(sizeof(float)))
        return false;
    setVertexData(frame->vertexData); // implicitly shared: no copy of the float data
    setBounds(frame->boundsMin, frame->boundsMax);
    update();
    return true;
}

} // namespace drape::widget
