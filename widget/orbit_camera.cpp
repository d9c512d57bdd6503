#include "widget/orbit_camera.hpp"

#include "widget/drape_frame.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace drape::widget {

double OrbitCamera::labFieldOfView()
{
    return 2.0 * std::atan(436.0 / 1280.0);
}

void OrbitCamera::setPreset(Preset p)
{
    using std::numbers::pi;
    target = Eigen::Vector3d::Zero();
    fovY = labFieldOfView();
    switch (p) {
    case Preset::Top: // 1.0 m above the floor = 0.88 m above the pedestal top
        azimuth = -pi / 2;
        elevation = pi / 2;
        distance = 0.88;
        break;
    case Preset::Side:
        azimuth = -pi / 2;
        elevation = 0;
        distance = 1.0;
        break;
    case Preset::Iso: // (0.3536, -0.6124, 0.7071) = 1 m at azimuth -60, elevation 45 degrees
        azimuth = -pi / 3;
        elevation = pi / 4;
        distance = 1.0;
        break;
    case Preset::Close:
        azimuth = -pi / 3;
        elevation = pi / 4;
        distance = 0.6;
        break;
    }
}

void OrbitCamera::orbit(double dAzimuth, double dElevation)
{
    using std::numbers::pi;
    azimuth = std::remainder(azimuth + dAzimuth, 2 * pi);
    elevation = std::clamp(elevation + dElevation, -pi / 2, pi / 2);
}

void OrbitCamera::pan(double dx, double dy)
{
    // One view height at the target's depth spans 2 d tan(fov/2) metres.
    const double span = 2.0 * distance * std::tan(fovY / 2);
    target += (-dx * right() + dy * up()) * span;
}

void OrbitCamera::zoom(double factor)
{
    if (!(factor > 0) || !std::isfinite(factor)) return;
    distance = std::clamp(distance * factor, 0.02, 50.0);
}

Eigen::Vector3d OrbitCamera::direction() const
{
    return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth), std::sin(elevation)};
}

Eigen::Vector3d OrbitCamera::position() const
{
    return target + distance * direction();
}

Eigen::Vector3d OrbitCamera::up() const
{
    // d(direction)/d(elevation): defined at the poles too, so the top view has
    // a well-defined image up (+y at azimuth -90 degrees, as the lab's top camera).
    return {-std::sin(elevation) * std::cos(azimuth), -std::sin(elevation) * std::sin(azimuth), std::cos(elevation)};
}

Eigen::Vector3d OrbitCamera::right() const
{
    return (-direction()).cross(up());
}

QVector3D OrbitCamera::scenePosition() const
{
    const Eigen::Vector3d p = position();
    return toScene(p.x(), p.y(), p.z());
}

QQuaternion OrbitCamera::sceneRotation() const
{
    const Eigen::Vector3d r = right(), u = up(), b = direction();
    return QQuaternion::fromAxes(toScene(r.x(), r.y(), r.z()), toScene(u.x(), u.y(), u.z()),
                                 toScene(b.x(), b.y(), b.z()));
}

double OrbitCamera::fovYDegrees() const
{
    return fovY * 180.0 / std::numbers::pi;
}

void OrbitCamera::ray(double px, double py, double w, double h, Eigen::Vector3d& origin, Eigen::Vector3d& dir) const
{
    const double t = std::tan(fovY / 2);
    const double aspect = h > 0 ? w / h : 1.0;
    const double nx = (2.0 * px / std::max(w, 1.0) - 1.0) * t * aspect;
    const double ny = (1.0 - 2.0 * py / std::max(h, 1.0)) * t;
    origin = position();
    dir = (-direction() + nx * right() + ny * up()).normalized();
}

bool OrbitCamera::project(const Eigen::Vector3d& p, double w, double h, double& px, double& py) const
{
    const Eigen::Vector3d d = p - position();
    const double depth = d.dot(-direction());
    if (depth <= 1e-9) return false;
    const double t = std::tan(fovY / 2);
    const double aspect = h > 0 ? w / h : 1.0;
    const double nx = d.dot(right()) / depth / (t * aspect);
    const double ny = d.dot(up()) / depth / t;
    px = (nx + 1.0) / 2.0 * w;
    py = (1.0 - ny) / 2.0 * h;
    return true;
}

} // namespace drape::widget
