// The drapemeter scene for Qt Quick hosts: the one scene view (SceneView.qml)
// showing a DrapeController's scene - the same view DrapeView shows.
import QtQuick
import Drapekit

SceneView {
    id: root
    required property DrapeController controller
    scene: root.controller ? root.controller.scene : null
}
