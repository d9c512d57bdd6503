#pragma once
// Picking on a triangle mesh in world coordinates: the camera ray against every
// triangle (both faces, so it picks what is visible on a double-sided cloth).
#include "widget/drape_widget_export.hpp"
#include "widget/orbit_camera.hpp"

#include "engine/cloth/mesh.hpp"

namespace drape::widget {

/// The vertex of the nearest triangle hit by the ray through view point (x, y)
/// of a w x h view that is closest to the hit point, or -1 when the ray misses.
DRAPE_WIDGET_EXPORT int pickVertex(const OrbitCamera& camera, const cloth::Positions& X, const cloth::Triangles& F, double x, double y,
               double w, double h);

} // namespace drape::widget
