#include "widget/scene_widget.hpp"

#include "widget/drape_qml.hpp"
#include "widget/scene.hpp"

#include <QQmlContext>
#include <QQmlEngine>
#include <QQuickWidget>
#include <QVBoxLayout>

namespace drape::widget {

SceneWidget::SceneWidget(Scene* scene, QWidget* parent) : QWidget(parent), m_scene(scene)
{
    registerDrapeQmlTypes();
    if (!m_scene) m_scene = new Scene(this);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    m_quick = new QQuickWidget(this);
    m_quick->setObjectName(QStringLiteral("sceneQuickWidget"));
    m_quick->setResizeMode(QQuickWidget::SizeRootObjectToView);
    m_quick->setFocusPolicy(Qt::StrongFocus);
    // The view reads its scene from this context property (set before the QML is
    // created, so no binding ever sees a null scene).
    m_quick->rootContext()->setContextProperty(QStringLiteral("sceneWidgetScene"), m_scene);
    m_quick->setSource(QUrl(QStringLiteral("qrc:/drapekit/qml/SceneWidgetRoot.qml")));
    for (const QQmlError& e : m_quick->errors()) qWarning("SceneView.qml: %s", qPrintable(e.toString()));
    layout->addWidget(m_quick);
}

SceneWidget::~SceneWidget()
{
    // The view references the scene's geometry: take it down first.
    delete m_quick;
    m_quick = nullptr;
}

QImage SceneWidget::grabFrame()
{
    return m_quick ? m_quick->grabFramebuffer() : QImage();
}

} // namespace drape::widget
