#pragma once
// The QML module "Drapekit" (qt_add_qml_module in widget/CMakeLists.txt):
//
//   import Drapekit
//   DrapeScene { anchors.fill: parent
//                controller: DrapeController { fabricPreset: "cotton"; integrator: Drape.Static; running: true } }
//
// An application linking drape_widget imports it without an import path (its
// qmldir is in the library's resources, on Qt's default import path); a
// QML-only host finds the installed module through QML_IMPORT_PATH
// (<prefix>/<libdir>/qt6/qml). Types: DrapeController (creatable), Drape (the
// enums), SceneView (the Qt Quick 3D view of a Scene: items, camera, mouse),
// DrapeScene (a SceneView of a controller's scene); Scene, SceneItem,
// MeshGeometry and LineGeometry (uncreatable).
#include "widget/drape_widget_export.hpp"

namespace drape::widget {

/// Registers the module's C++ types now (they are also registered when the
/// library loads). Safe to call more than once.
DRAPE_WIDGET_EXPORT void registerDrapeQmlTypes();

} // namespace drape::widget
