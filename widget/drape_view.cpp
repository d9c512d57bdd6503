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

    auto* c = m_controller;
    connect(c, &DrapeController::fabricPresetChanged, this, &DrapeView::fabricPresetChanged);
    connect(c, &DrapeController::sampleDiameterChanged, this, &DrapeView::sampleDiameterChanged);
    connect(c, &DrapeController::discDiameterChanged, this, &DrapeView::discDiameterChanged);
    connect(c, &DrapeController::gridSizeChanged, this, &DrapeView::gridSizeChanged);
    connect(c, &DrapeController::clothShapeChanged, this, &DrapeView::clothShapeChanged);
    connect(c, &DrapeController::integratorChanged, this, &DrapeView::integratorChanged);
    connect(c, &DrapeController::textureChanged, this, &DrapeView::textureChanged);
    connect(c, &DrapeController::runningChanged, this, &DrapeView::runningChanged);
    connect(c, &DrapeController::timeStepChanged, this, &DrapeView::timeStepChanged);
    connect(c, &DrapeController::restSpeedChanged, this, &DrapeView::restSpeedChanged);
    connect(c, &DrapeController::restResidualChanged, this, &DrapeView::restResidualChanged);
    connect(c, &DrapeController::viewPresetChanged, this, &DrapeView::viewPresetChanged);
    connect(c, &DrapeController::clothColorChanged, this, &DrapeView::clothColorChanged);
    connect(c, &DrapeController::backgroundColorChanged, this, &DrapeView::backgroundColorChanged);
    connect(c, &DrapeController::showCollidersChanged, this, &DrapeView::showCollidersChanged);
    connect(c, &DrapeController::showOutlinesChanged, this, &DrapeView::showOutlinesChanged);
    connect(c, &DrapeController::pickEnabledChanged, this, &DrapeView::pickEnabledChanged);
    connect(c, &DrapeController::labFloorChanged, this, &DrapeView::labFloorChanged);
    connect(c, &DrapeController::progress, this, &DrapeView::progress);
    connect(c, &DrapeController::restReached, this, &DrapeView::restReached);
    connect(c, &DrapeController::errorOccurred, this, &DrapeView::errorOccurred);
    connect(c, &DrapeController::resultsSaved, this, &DrapeView::resultsSaved);
    connect(c, &DrapeController::jobProgress, this, &DrapeView::jobProgress);
    connect(c, &DrapeController::jobFinished, this, &DrapeView::jobFinished);
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
