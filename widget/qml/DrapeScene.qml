// The drape scene: cloth, colliders, pins, outlines, camera and mouse handling.
// Scene units are metres, y up (the controller converts from Drapekit's z-up world).
import QtQuick
import QtQuick3D
import Drapekit 1.0

Item {
    id: root
    required property DrapeController controller
    /// Shows the status line (fabric, time, speed) in the bottom-left corner.
    property bool showStatus: true
    implicitWidth: 480
    implicitHeight: 360

    View3D {
        id: view
        objectName: "drapeView3D"
        anchors.fill: parent
        camera: camera
        environment: SceneEnvironment {
            backgroundMode: SceneEnvironment.Color
            clearColor: root.controller.backgroundColor
        }

        PerspectiveCamera {
            id: camera
            position: root.controller.cameraPosition
            rotation: root.controller.cameraRotation
            fieldOfView: root.controller.fieldOfView
            fieldOfViewOrientation: PerspectiveCamera.Vertical
            clipNear: 0.005
            clipFar: 20
        }

        // Key light from above the iso camera's side, a weaker fill from the
        // opposite side and below, and some ambient so folds facing away stay readable.
        DirectionalLight {
            eulerRotation: Qt.vector3d(-55, -35, 0)
            brightness: 1.0
            ambientColor: Qt.rgba(0.28, 0.28, 0.28, 1)
        }
        DirectionalLight {
            eulerRotation: Qt.vector3d(25, 150, 0)
            brightness: 0.35
        }

        Model {
            id: clothModel
            objectName: "cloth"
            geometry: root.controller.clothGeometry
            materials: PrincipledMaterial {
                // Both faces drawn and lit: Qt Quick 3D flips the normal on back faces.
                cullMode: Material.NoCulling
                baseColor: root.controller.hasTexture ? "white" : root.controller.clothColor
                baseColorMap: root.controller.hasTexture ? clothTexture : null
                roughness: 0.9
                metalness: 0.0
                specularAmount: 0.1
            }
        }
        Texture {
            id: clothTexture
            textureData: root.controller.textureData
            generateMipmaps: true
            mipFilter: Texture.Linear
        }

        Repeater3D {
            model: root.controller.showColliders ? root.controller.colliders : []
            delegate: Model {
                required property var modelData
                objectName: "collider-" + modelData.kind
                source: modelData.source
                position: modelData.position
                scale: modelData.scale
                rotation: modelData.rotation
                materials: PrincipledMaterial {
                    baseColor: modelData.color
                    roughness: 0.95
                    specularAmount: 0.05
                    cullMode: Material.NoCulling
                }
            }
        }

        Model {
            objectName: "floorBoards"
            visible: root.controller.showColliders && root.controller.floorBoardsVisible
            geometry: root.controller.floorBoards
            materials: PrincipledMaterial {
                baseColor: "#1e1e1e"
                roughness: 0.95
                specularAmount: 0.05
            }
        }

        Repeater3D {
            model: root.controller.pinnedPositions
            delegate: Model {
                required property var modelData
                source: "#Sphere"
                position: modelData
                scale: Qt.vector3d(0.00008, 0.00008, 0.00008) // 4 mm radius
                materials: PrincipledMaterial {
                    baseColor: "#ffd000"
                    lighting: PrincipledMaterial.NoLighting
                }
            }
        }

        Model {
            objectName: "simulatedOutline"
            visible: root.controller.showOutlines
            geometry: root.controller.simulatedOutline
            materials: PrincipledMaterial {
                baseColor: "#ff8c00"
                lighting: PrincipledMaterial.NoLighting
            }
        }
        Model {
            objectName: "measuredOutline"
            visible: root.controller.showOutlines
            geometry: root.controller.measuredOutline
            materials: PrincipledMaterial {
                baseColor: "#20a0ff"
                lighting: PrincipledMaterial.NoLighting
            }
        }
    }

    MouseArea {
        id: mouse
        anchors.fill: parent
        acceptedButtons: Qt.LeftButton | Qt.RightButton | Qt.MiddleButton
        property point start
        property point last
        property bool dragged: false
        onPressed: (m) => {
            start = Qt.point(m.x, m.y)
            last = start
            dragged = false
        }
        onPositionChanged: (m) => {
            if (!dragged && Math.abs(m.x - start.x) + Math.abs(m.y - start.y) > 4)
                dragged = true
            if (!dragged)
                return
            const dx = m.x - last.x, dy = m.y - last.y
            if ((m.buttons & Qt.LeftButton) && !(m.modifiers & Qt.ShiftModifier))
                root.controller.orbit(dx, dy)
            else
                root.controller.pan(dx, dy, height)
            last = Qt.point(m.x, m.y)
        }
        onReleased: (m) => {
            if (!dragged && m.button === Qt.LeftButton && root.controller.pickEnabled)
                root.controller.togglePinAt(m.x, m.y, width, height)
        }
        onWheel: (w) => root.controller.zoom(w.angleDelta.y)
    }

    Text {
        visible: root.showStatus
        anchors.left: parent.left
        anchors.bottom: parent.bottom
        anchors.margins: 6
        color: "#e0e0e0"
        style: Text.Outline
        styleColor: "#202020"
        font.pixelSize: 11
        text: root.controller.statusText
    }
}
