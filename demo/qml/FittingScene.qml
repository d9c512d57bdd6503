// The fitting scene: mannequin (or round table), floor and the draped garment.
// Scene units are metres, y up; `fitting` (FittingSceneState) converts from
// Drapekit's z-up world and owns the camera.
import QtQuick
import QtQuick3D

Item {
    id: root
    implicitWidth: 560
    implicitHeight: 640

    View3D {
        id: view
        objectName: "fittingView3D"
        anchors.fill: parent
        environment: SceneEnvironment {
            backgroundMode: SceneEnvironment.Color
            clearColor: "#2b2f36"
            antialiasingMode: SceneEnvironment.MSAA
            antialiasingQuality: SceneEnvironment.Medium
        }
        camera: camera

        PerspectiveCamera {
            id: camera
            position: fitting.cameraPosition
            rotation: fitting.cameraRotation
            fieldOfView: fitting.fieldOfView
            fieldOfViewOrientation: PerspectiveCamera.Vertical
            clipNear: 0.02
            clipFar: 50
        }

        // Key light from the front-left above, a fill from behind, some ambient.
        DirectionalLight {
            eulerRotation: Qt.vector3d(-40, -30, 0)
            brightness: 1.0
            ambientColor: Qt.rgba(0.3, 0.3, 0.3, 1)
        }
        DirectionalLight {
            eulerRotation: Qt.vector3d(-20, 160, 0)
            brightness: 0.4
        }

        Model {
            objectName: "floor"
            source: "#Rectangle"
            eulerRotation.x: -90
            scale: Qt.vector3d(0.06, 0.06, 1) // 6 m square
            materials: PrincipledMaterial {
                baseColor: "#3a3f47"
                roughness: 1.0
                specularAmount: 0.0
            }
        }

        Model {
            objectName: "body"
            visible: fitting.bodyVisible
            geometry: fitting.bodyGeometry
            materials: PrincipledMaterial {
                baseColor: "#d9c7b8"
                roughness: 0.8
                specularAmount: 0.15
                cullMode: Material.NoCulling
            }
        }

        Model {
            objectName: "table"
            visible: fitting.tableVisible
            source: "#Cylinder"
            position: fitting.tablePosition
            scale: fitting.tableScale
            materials: PrincipledMaterial {
                baseColor: "#8a6a4a"
                roughness: 0.7
            }
        }

        Model {
            objectName: "cloth"
            geometry: fitting.clothGeometry
            materials: PrincipledMaterial {
                // Both faces drawn and lit: the inside of a skirt shows at the hem.
                cullMode: Material.NoCulling
                baseColor: fitting.clothColor
                roughness: 0.9
                metalness: 0.0
                specularAmount: 0.1
            }
        }
    }

    MouseArea {
        anchors.fill: parent
        acceptedButtons: Qt.LeftButton
        property point last
        onPressed: (m) => last = Qt.point(m.x, m.y)
        onPositionChanged: (m) => {
            fitting.orbit(m.x - last.x, m.y - last.y)
            last = Qt.point(m.x, m.y)
        }
        onWheel: (w) => fitting.zoom(w.angleDelta.y)
    }

    Text {
        anchors.left: parent.left
        anchors.top: parent.top
        anchors.margins: 8
        color: "#f0f0f0"
        style: Text.Outline
        styleColor: "#202020"
        font.pixelSize: 15
        text: fitting.title
    }
    Text {
        anchors.left: parent.left
        anchors.bottom: parent.bottom
        anchors.margins: 6
        color: "#e0e0e0"
        style: Text.Outline
        styleColor: "#202020"
        font.pixelSize: 11
        text: fitting.status
    }
}
