// Root of SceneWidget's QQuickWidget: the view bound to the widget's scene.
import Drapekit

SceneView {
    scene: sceneWidgetScene
}
