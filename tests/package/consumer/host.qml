// Drapekit in a QML-only application: the module comes from QML_IMPORT_PATH.
import QtQuick
import Drapekit

DrapeScene {
    width: 480
    height: 360
    controller: DrapeController {
        fabricPreset: "silk"       // a starter fabric by its short name
        gridSize: 17
        integrator: Drape.Static
        viewPreset: Drape.Top
        running: true
    }
}
