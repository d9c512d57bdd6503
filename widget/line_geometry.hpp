#pragma once
// A closed polyline drawn as line segments (outlines: measured vs simulated).
#include "widget/drape_widget_export.hpp"
#include <QtQml/qqmlregistration.h>
#include "engine/cloth/metrics.hpp"

#include <QQuick3DGeometry>

namespace drape::widget {

class DRAPE_WIDGET_EXPORT LineGeometry : public QQuick3DGeometry {
    Q_OBJECT
    QML_ELEMENT
    QML_UNCREATABLE("use Scene.items")
    Q_PROPERTY(int pointCount READ pointCount NOTIFY pointsChanged)
public:
    explicit LineGeometry(QQuick3DObject* parent = nullptr);
    int pointCount() const { return m_count; }
    /// Polygon in the world's horizontal plane [m], drawn closed at height z [m].
    void setPolygon(const cloth::Polygon2& poly, double z);
    void clearPolygon();

signals:
    void pointsChanged();

private:
    int m_count = 0;
};

} // namespace drape::widget
