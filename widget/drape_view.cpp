#include "widget/drape_view.hpp"

#include "widget/drape_qml.hpp"

#include <QQmlContext>
#include <QQmlEngine>
#include <QQuickItem>
#include <QQuickWidget>
#include <QVBoxLayout>

namespace drape::widget {

DrapeView::DrapeView(QWidget* parent) : QWidget(parent)
{
    registerDrapeQmlTypes();
    m_controller = new DrapeController(this);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    m_quick = new QQuickWidget(this);
    m_quick->setObjectName(QStringLiteral("drapeQuickWidget"));
    m_quick->setResizeMode(QQuickWidget::SizeRootObjectToView);
    m_quick->setFocusPolicy(Qt::StrongFocus);
    // The scene reads its controller from this context property (set before the
    // QML is created, so no binding ever sees a null controller).
    m_quick->rootContext()->setContextProperty(QStringLiteral("drapeViewController"), m_controller);
    m_quick->setSource(QUrl(QStringLiteral("qrc:/drapekit/qml/DrapeViewRoot.qml")));
    for (const QQmlError& e : m_quick->errors())
        emit errorOccurred(QStringLiteral("scene: %1").arg(e.toString()));
    layout->addWidget(m_quick);

    // Every property's ...Changed signal and the other public signals, as the controller emits them.
    auto* c = m_controller;
#define DRAPE_FORWARD_CHANGED(Type, Arg, name, setter, init) \
    connect(c, &DrapeController::name##Changed, this, &DrapeView::name##Changed);
    DRAPE_VIEW_PROPERTIES(DRAPE_FORWARD_CHANGED)
#undef DRAPE_FORWARD_CHANGED
#define DRAPE_FORWARD_SIGNAL(name, params) connect(c, &DrapeController::name, this, &DrapeView::name);
    DRAPE_VIEW_SIGNALS(DRAPE_FORWARD_SIGNAL)
#undef DRAPE_FORWARD_SIGNAL
}

DrapeView::~DrapeView()
{
    // The scene references the controller's geometry: take it down first.
    delete m_quick;
    m_quick = nullptr;
}

QImage DrapeView::grabFrame()
{
    return m_quick ? m_quick->grabFramebuffer() : QImage();
}

} // namespace drape::widget
