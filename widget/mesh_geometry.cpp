#include "widget/mesh_geometry.hpp"

namespace drape::widget {

MeshGeometry::MeshGeometry(QQuick3DObject* parent) : QQuick3DGeometry(parent)
{
    setPrimitiveType(PrimitiveType::Triangles);
    setStride(kFloatsPerVertex * int(sizeof(float)));
    addAttribute(Attribute::PositionSemantic, 0, Attribute::F32Type);
    addAttribute(Attribute::NormalSemantic, 3 * sizeof(float), Attribute::F32Type);
    addAttribute(Attribute::TexCoord0Semantic, 6 * sizeof(float), Attribute::F32Type);
    addAttribute(Attribute::IndexSemantic, 0, Attribute::U32Type);
}

void MeshGeometry::setTopology(const PackedTopology& topology)
{
    m_vertexCount = topology.vertexCount;
    m_triangleCount = topology.triangleCount;
    setIndexData(topology.indices);
    // Keep the buffers consistent: no vertices until the first frame of this topology.
    setVertexData(QByteArray());
    emit meshChanged();
    update();
}

bool MeshGeometry::setVertices(const PackedVertices& vertices)
{
    if (vertices.vertexCount != m_vertexCount ||
        vertices.data.size() != qsizetype(m_vertexCount) * kFloatsPerVertex * qsizetype(sizeof(float)))
        return false;
    setVertexData(vertices.data); // implicitly shared: no copy of the float data
    setBounds(vertices.boundsMin, vertices.boundsMax);
    update();
    return true;
}

} // namespace drape::widget
