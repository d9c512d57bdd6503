#include "widget/frame_packer.hpp"

#include "widget/world_frame.hpp"

#include <Eigen/Geometry>

#include <algorithm>

namespace drape::widget {

PackedTopology packTopology(const cloth::Triangles& F, int vertexCount)
{
    PackedTopology t;
    t.vertexCount = vertexCount;
    t.triangleCount = int(F.rows());
    t.indices.resize(qsizetype(F.size()) * qsizetype(sizeof(quint32)));
    auto* idx = reinterpret_cast<quint32*>(t.indices.data());
    for (Eigen::Index i = 0; i < F.rows(); ++i)
        for (int k = 0; k < 3; ++k) idx[3 * i + k] = quint32(F(i, k));
    return t;
}

std::vector<float> texcoordsFromMaterial(const Eigen::MatrixX2d& uv, int n)
{
    std::vector<float> tex(std::size_t(2 * n), 0.0f);
    if (uv.rows() != n || n == 0) return tex;
    const Eigen::Vector2d lo = uv.colwise().minCoeff(), hi = uv.colwise().maxCoeff();
    const double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1e-12});
    for (int i = 0; i < n; ++i) {
        tex[std::size_t(2 * i)] = float((uv(i, 0) - lo.x()) / span);
        tex[std::size_t(2 * i + 1)] = float((uv(i, 1) - lo.y()) / span);
    }
    return tex;
}

PackedVertices packVertices(const cloth::Positions& X, const cloth::Triangles& F, const std::vector<float>& texcoord)
{
    const int n = int(X.rows());
    const bool hasTex = texcoord.size() == std::size_t(2 * n);
    // Smooth normals: area-weighted sum of the incident triangles' normals.
    cloth::Positions nrm = cloth::Positions::Zero(n, 3);
    for (Eigen::Index t = 0; t < F.rows(); ++t) {
        const int a = F(t, 0), b = F(t, 1), c = F(t, 2);
        const Eigen::Vector3d fa = (X.row(b) - X.row(a)).cross(X.row(c) - X.row(a));
        nrm.row(a) += fa;
        nrm.row(b) += fa;
        nrm.row(c) += fa;
    }
    PackedVertices v;
    v.vertexCount = n;
    v.data.resize(qsizetype(n) * kFloatsPerVertex * qsizetype(sizeof(float)));
    auto* out = reinterpret_cast<float*>(v.data.data());
    QVector3D lo(1e9f, 1e9f, 1e9f), hi(-1e9f, -1e9f, -1e9f);
    for (int i = 0; i < n; ++i) {
        const QVector3D p = toScene(X(i, 0), X(i, 1), X(i, 2));
        const double len = nrm.row(i).norm();
        const QVector3D q = len > 0 ? toScene(nrm(i, 0) / len, nrm(i, 1) / len, nrm(i, 2) / len) : QVector3D(0, 1, 0);
        float* o = out + std::ptrdiff_t(i) * kFloatsPerVertex;
        o[0] = p.x(); o[1] = p.y(); o[2] = p.z();
        o[3] = q.x(); o[4] = q.y(); o[5] = q.z();
        o[6] = hasTex ? texcoord[std::size_t(2 * i)] : 0.0f;
        o[7] = hasTex ? texcoord[std::size_t(2 * i + 1)] : 0.0f;
        lo = QVector3D(std::min(lo.x(), p.x()), std::min(lo.y(), p.y()), std::min(lo.z(), p.z()));
        hi = QVector3D(std::max(hi.x(), p.x()), std::max(hi.y(), p.y()), std::max(hi.z(), p.z()));
    }
    v.boundsMin = lo;
    v.boundsMax = hi;
    return v;
}

} // namespace drape::widget
