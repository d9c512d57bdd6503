#pragma once
// QML types for Qt Quick hosts: call registerDrapeQmlTypes() once before
// loading QML, then
//
//   import Drapekit 1.0
//   DrapeScene { anchors.fill: parent; controller: DrapeController { gridSize: 40; running: true } }
//
// Types: DrapeController (creatable); SceneView (the Qt Quick 3D view of a
// Scene: items, camera, mouse) and DrapeScene (a SceneView of a controller's
// scene); Scene, SceneItem, MeshGeometry and LineGeometry (uncreatable).
namespace drape::widget {

/// Registers the "Drapekit 1.0" QML module. Safe to call more than once.
void registerDrapeQmlTypes();

} // namespace drape::widget
