// The one 3-D view of a Scene (widget/scene.hpp): its items, markers, camera,
// lights, mouse handling and text. DrapeView, DrapeScene and the fitting demo
// all draw through this file. Scene units are metres, y up (the Scene converts
// from Drapekit's z-up world).
import QtQuick
import QtQuick3D
import Drapekit

Item {
    id: root
    required property Scene scene
    /// Shows the scene's status line in the bottom-left corner.
    property bool showStatus: true
    implicitWidth: 480
    implicitHeight: 360

    View3D {
        id: view
        objectName: "sceneView3D"
        anchors.fill: parent
        camera: camera
        environment: SceneEnvironment {
            backgroundMode: SceneEnvironment.Color
            clearColor: root.scene ? root.scene.backgroundColor : "black"
            antialiasingMode: root.scene && root.scene.antialiasing ? SceneEnvironment.MSAA : SceneEnvironment.NoAA
            antialiasingQuality: SceneEnvironment.Medium
        }

        PerspectiveCamera {
            id: camera
            position: root.scene ? root.scene.cameraPosition : Qt.vector3d(0, 0, 1)
            rotation: root.scene ? root.scene.cameraRotation : Qt.quaternion(1, 0, 0, 0)
            fieldOfView: root.scene ? root.scene.fieldOfView : 40
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

        Repeater3D {
            model: root.scene ? root.scene.items : null
            delegate: Model {
                id: entry
                required property SceneItem sceneItem
                objectName: sceneItem.name
                visible: sceneItem.visible
                geometry: sceneItem.geometry
                source: sceneItem.source
                position: sceneItem.position
                scale: sceneItem.scale
                rotation: sceneItem.rotation
                materials: PrincipledMaterial {
                    // Double-sided items are lit on both faces: Qt Quick 3D flips the normal on back faces.
                    cullMode: entry.sceneItem.doubleSided ? Material.NoCulling : Material.BackFaceCulling
                    lighting: entry.sceneItem.lit ? PrincipledMaterial.FragmentLighting : PrincipledMaterial.NoLighting
                    baseColor: entry.sceneItem.textured ? "white" : entry.sceneItem.color
                    baseColorMap: entry.sceneItem.textured ? itemTexture : null
                    roughness: entry.sceneItem.roughness
                    metalness: 0.0
                    specularAmount: entry.sceneItem.specularAmount
                }
                Texture {
                    id: itemTexture
                    textureData: SceneTexture { item: entry.sceneItem }
                    generateMipmaps: true
                    mipFilter: Texture.Linear
                }
            }
        }

        Repeater3D {
            model: root.scene ? root.scene.markers : []
            delegate: Model {
                required property var modelData
                source: "#Sphere"
                position: modelData
                scale: root.scene.markerScale
                materials: PrincipledMaterial {
                    baseColor: root.scene.markerColor
                    lighting: PrincipledMaterial.NoLighting
                }
            }
        }
    }

    MouseArea {
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
            if (!dragged || !root.scene)
                return
            const dx = m.x - last.x, dy = m.y - last.y
            if ((m.buttons & Qt.LeftButton) && !(m.modifiers & Qt.ShiftModifier))
                root.scene.orbit(dx, dy)
            else
                root.scene.pan(dx, dy, height)
            last = Qt.point(m.x, m.y)
        }
        onReleased: (m) => {
            if (!dragged && m.button === Qt.LeftButton && root.scene)
                root.scene.click(m.x, m.y, width, height)
        }
        onWheel: (w) => { if (root.scene) root.scene.zoom(w.angleDelta.y) }
    }

    Text {
        visible: text !== ""
        anchors.left: parent.left
        anchors.top: parent.top
        anchors.margins: 8
        color: "#f0f0f0"
        style: Text.Outline
        styleColor: "#202020"
        font.pixelSize: 15
        text: root.scene ? root.scene.title : ""
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
        text: root.scene ? root.scene.statusText : ""
    }
}
