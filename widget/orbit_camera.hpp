#pragma once
// Orbit camera around a target, in Drapekit's world frame (z up, metres), with
// the lab's three camera stations as presets. Pure maths (no Qt Quick), so the
// picking ray and the projection used by tests are the same code that places
// the Qt Quick 3D camera.
#include "widget/drape_widget_export.hpp"
#include <Eigen/Core>

#include <QQuaternion>
#include <QVector3D>

namespace drape::widget {

class DRAPE_WIDGET_EXPORT OrbitCamera {
public:
    enum class Preset { Top, Side, Iso, Close };

    /// Vertical field of view of the lab camera [rad]: fx = 1280 px on an
    /// 872 px high image, 2 atan(436 / 1280).
    static double labFieldOfView();

    /// Top: 0.88 m above the pedestal top looking down (image right +x, up +y);
    /// side: from (0, -1, 0) m looking along +y (right +x, up +z);
    /// iso: from (0.3536, -0.6124, 0.7071) m looking at the origin (up ~ +z);
    /// close: the iso direction at 0.6 m, filling a widget with the specimen (not a lab station).
    void setPreset(Preset p);

    /// Turns about the target [rad]; elevation is clamped to [-pi/2, pi/2].
    void orbit(double dAzimuth, double dElevation);
    /// Moves the target in the view plane by fractions of the view height.
    void pan(double dx, double dy);
    /// Multiplies the distance by `factor` (> 0), clamped to [0.02, 50] m.
    void zoom(double factor);

    Eigen::Vector3d target = Eigen::Vector3d::Zero(); ///< [m]
    double azimuth = -1.5707963267948966;   ///< [rad] from +x towards +y
    double elevation = 1.5707963267948966;  ///< [rad] above the horizontal
    double distance = 0.88;                 ///< [m] from the target
    double fovY = labFieldOfView();         ///< vertical field of view [rad]

    Eigen::Vector3d direction() const; ///< unit vector target -> camera
    Eigen::Vector3d position() const;  ///< [m]
    Eigen::Vector3d up() const;        ///< image up, unit
    Eigen::Vector3d right() const;     ///< image right, unit

    QVector3D scenePosition() const;   ///< Qt Quick 3D (y up) [m]
    QQuaternion sceneRotation() const; ///< Qt Quick 3D camera rotation (looks along local -z)
    double fovYDegrees() const;

    /// Ray through view point (px, py) of a w x h view (pixels, y down, (0,0)
    /// the top-left corner): origin = camera position, unit direction.
    void ray(double px, double py, double w, double h, Eigen::Vector3d& origin, Eigen::Vector3d& dir) const;
    /// World point -> view point; false when the point is behind the camera.
    bool project(const Eigen::Vector3d& p, double w, double h, double& px, double& py) const;
};

} // namespace drape::widget
