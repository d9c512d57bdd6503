// Root of SceneWidget's QQuickWidget: the view bound to the widget's scene.
import Drapekit 1.0

SceneView {
    scene: sceneWidgetScene
}
