#pragma once
// SceneWidget: a QWidget showing a Scene through qml/SceneView.qml in a
// QQuickWidget. DrapeView embeds one for its controller's scene; the fitting
// demo shows its bodies and garments in others.
#include "widget/drape_widget_export.hpp"
#include <QImage>
#include <QWidget>

class QQuickWidget;

namespace drape::widget {

class Scene;

class DRAPE_WIDGET_EXPORT SceneWidget : public QWidget {
    Q_OBJECT
public:
    /// Shows `scene`, or a scene of its own when null.
    explicit SceneWidget(Scene* scene = nullptr, QWidget* parent = nullptr);
    ~SceneWidget() override;

    Scene* scene() const { return m_scene; }
    QQuickWidget* quickWidget() const { return m_quick; }
    /// The rendered view as an image (renders now; for screenshots and tests).
    QImage grabFrame();

    QSize sizeHint() const override { return {480, 360}; }
    QSize minimumSizeHint() const override { return {120, 90}; }

private:
    Scene* m_scene = nullptr;
    QQuickWidget* m_quick = nullptr;
};

} // namespace drape::widget
