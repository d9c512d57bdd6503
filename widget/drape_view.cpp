#include "widget/drape_view.hpp"

#include <QVBoxLayout>

namespace drape::widget {

DrapeView::DrapeView(QWidget* parent) : QWidget(parent)
{
    m_controller = new DrapeController(this);
    m_view = new SceneWidget(m_controller->scene(), this);
    auto* layout = new QVBoxLayout(this);
    layout->setContentsMargins(0, 0, 0, 0);
    layout->addWidget(m_view);

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
    // The view draws the controller's scene: take it down first.
    delete m_view;
    m_view = nullptr;
}

} // namespace drape::widget
