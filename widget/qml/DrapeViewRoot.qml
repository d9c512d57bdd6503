// Root of DrapeView's QQuickWidget: the scene bound to the widget's controller.
import Drapekit 1.0

DrapeScene {
    controller: drapeViewController
}
