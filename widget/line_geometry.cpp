#include "widget/line_geometry.hpp"

#include "widget/drape_frame.hpp"

#include <cmath>
#include <limits>

namespace drape::widget {

LineGeometry::LineGeometry(QQuick3DObject* parent) : QQuick3DGeometry(parent)
{
    setPrimitiveType(PrimitiveType::Lines);
    setStride(3 * int(sizeof(float)));
    addAttribute(Attribute::PositionSemantic, 0, Attribute::F32Type);
}

void LineGeometry::setPolygon(const cloth::Polygon2& poly, double z)
{
    QByteArray data;
    const qsizetype n = qsizetype(poly.size());
    data.resize(n * 2 * 3 * qsizetype(sizeof(float)));
    auto* f = reinterpret_cast<float*>(data.data());
    QVector3D lo(1e9f, 1e9f, 1e9f), hi(-1e9f, -1e9f, -1e9f);
    qsizetype used = 0;
    for (qsizetype i = 0; i < n; ++i) {
        const auto& a = poly[std::size_t(i)];
        const auto& b = poly[std::size_t((i + 1) % n)];
        if (!a.allFinite() || !b.allFinite()) continue; // rays without a hit
        for (const auto* p : {&a, &b}) {
            const QVector3D s = toScene(p->x(), p->y(), z);
            f[used * 3 + 0] = s.x();
            f[used * 3 + 1] = s.y();
            f[used * 3 + 2] = s.z();
            lo = QVector3D(std::min(lo.x(), s.x()), std::min(lo.y(), s.y()), std::min(lo.z(), s.z()));
            hi = QVector3D(std::max(hi.x(), s.x()), std::max(hi.y(), s.y()), std::max(hi.z(), s.z()));
            ++used;
        }
    }
    data.resize(used * 3 * qsizetype(sizeof(float)));
    setVertexData(data);
    if (used > 0) setBounds(lo, hi);
    m_count = int(used / 2);
    emit pointsChanged();
    update();
}

void LineGeometry::clearPolygon()
{
    if (m_count == 0) return;
    setVertexData(QByteArray());
    m_count = 0;
    emit pointsChanged();
    update();
}

} // namespace drape::widget
