#include "demo/fitting_view.hpp"

#include "widget/rest_job.hpp"
#include "widget/scene.hpp"

namespace drape::demo {

QString toString(GarmentChoice g)
{
    switch (g) {
    case GarmentChoice::Skirt: return QStringLiteral("skirt");
    case GarmentChoice::Tablecloth: return QStringLiteral("tablecloth");
    case GarmentChoice::Imported: return QStringLiteral("garment");
    }
    return {};
}

FittingView::FittingView(QWidget* parent) : widget::DrapeView(parent)
{
    // A fitting room, not the lab: plain floor, the garment's own pins, no picking.
    setLabFloor(false);
    setPickEnabled(false);
    setBackgroundColor(QColor(0x2b, 0x2f, 0x36));
    setViewPreset(widget::Drape::Iso);
    // The garment drapes' rest criterion (importers::garment_rest_options): a
    // residual the eye cannot tell from exact rest.
    setRestResidual(importers::garment_rest_options().residual);
    controller()->scene()->setAntialiasing(true);
    connect(this, &widget::DrapeView::resultsReady, this, [this] {
        if (!m_pending) return;
        m_pending = false;
        // Ok: at rest, or stopped at the iteration budget without diverging (as importers' garment drapes count it).
        const cloth::SolverStatus st = lastStatus();
        const bool ok = st.outcome == cloth::SolverStatus::Outcome::Converged ||
                        st.outcome == cloth::SolverStatus::Outcome::NotConverged;
        emit finished(ok, widget::describeSolve(st));
    });
    connect(this, &widget::DrapeView::errorOccurred, this, [this](const QString& message) {
        // A solve that stopped at its budget reports results next; anything else ends the drape.
        if (!m_pending || message.startsWith(QLatin1String("static solver: not converged"))) return;
        m_pending = false;
        emit finished(false, message);
    });
}

void FittingView::cancel()
{
    widget::DrapeView::cancel();
    if (!m_pending) return;
    m_pending = false;
    emit finished(false, QStringLiteral("cancelled"));
}

FittingView::~FittingView() = default;

void FittingView::setMannequin(std::shared_ptr<const importers::Mannequin> m)
{
    m_mannequin = std::move(m);
    setBody(m_mannequin);
}

bool FittingView::drape(GarmentChoice garment, const library::FabricChoice& fabric, QString* error)
{
    if (m_pending || controller()->running()) {
        if (error) *error = tr("a drape is already running");
        return false;
    }
    if (garment == GarmentChoice::Skirt && !m_mannequin) {
        if (error) *error = tr("no mannequin loaded");
        return false;
    }
    if (garment == GarmentChoice::Imported && garmentFile().isEmpty()) {
        if (error) *error = tr("no garment mesh chosen");
        return false;
    }
    setScene(garment, fabric);
    m_pending = true;
    drapeToRest();
    return true;
}

bool FittingView::showUndraped(GarmentChoice garment, const library::FabricChoice& fabric)
{
    if (m_pending || controller()->running()) return false;
    if (garment == GarmentChoice::Skirt && !m_mannequin) return false;
    if (garment == GarmentChoice::Imported && garmentFile().isEmpty()) return false;
    setScene(garment, fabric);
    return true;
}

void FittingView::setScene(GarmentChoice garment, const library::FabricChoice& fabric)
{
    m_garment = garment;
    m_fabricName = QString::fromStdString(fabric.name);
    setFabric(fabric.preset, m_fabricName);
    setClothShape(garment == GarmentChoice::Skirt        ? widget::Drape::Skirt
                  : garment == GarmentChoice::Tablecloth ? widget::Drape::Tablecloth
                                                         : widget::Drape::GarmentMesh);
    controller()->scene()->setTitle(QStringLiteral("%1 · %2").arg(toString(garment), m_fabricName));
}

cloth::SolverStatus FittingView::lastStatus() const
{
    const widget::DrapeResultsPtr r = lastResults();
    return r ? r->status : cloth::SolverStatus{};
}

cloth::Positions FittingView::lastPositions() const
{
    return lastResults() && !m_pending ? lastResults()->x : cloth::Positions();
}

} // namespace drape::demo
