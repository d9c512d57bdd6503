#pragma once
// The one conversion between Drapekit's world frame (z up, metres, origin at the
// pedestal-top centre) and Qt Quick 3D's scene frame (y up, one unit = 1 m):
// scene = (x, z, -y), a rotation of -90 degrees about x.
#include <QVector3D>

namespace drape::widget {

/// World (z up) [m] -> Qt Quick 3D scene (y up) [m].
inline QVector3D toScene(double x, double y, double z)
{
    return {float(x), float(z), float(-y)};
}
/// Scene (y up) -> world (z up).
inline void toWorld(const QVector3D& s, double& x, double& y, double& z)
{
    x = s.x();
    y = -double(s.z());
    z = s.y();
}

} // namespace drape::widget
