#pragma once
// FittingView: one 3-D view of a fitting - the widget library's DrapeView with a
// body (setBody), a garment (the built-in circle skirt, the round tablecloth, or
// an imported garment mesh) and a fabric preset, draped to rest by the view's
// own worker thread (DrapeView::drapeToRest: the static solver, frames shown as
// it goes, a progress fraction, cancel). The demo adds nothing to the view: what
// it shows is what a CAD embedding DrapeView gets.
#include "engine/library/fabric_choices.hpp"
#include "importers/garment_scene.hpp"

#include "widget/drape_view.hpp"

#include <QColor>

#include <memory>

namespace drape::demo {

/// What a fitting drapes.
enum class GarmentChoice { Skirt, Tablecloth, Imported };

class FittingView : public widget::DrapeView {
    Q_OBJECT
public:
    explicit FittingView(QWidget* parent = nullptr);
    ~FittingView() override;

    /// Shows this body (null hides it). Takes effect for the next drape.
    void setMannequin(std::shared_ptr<const importers::Mannequin> m);
    std::shared_ptr<const importers::Mannequin> mannequin() const { return m_mannequin; }
    /// The garment mesh file for GarmentChoice::Imported (its top boundary is pinned).
    void setGarmentMeshFile(const QString& path) { setGarmentFile(path); }
    /// Drapes `garment` of `fabric` on the view's worker thread. Returns false
    /// with `error` set when a drape is already running or there is no body
    /// for a skirt; later trouble arrives as finished(false, message).
    bool drape(GarmentChoice garment, const library::FabricChoice& fabric, QString* error = nullptr);
    /// Shows `garment` of `fabric` as it starts (the skirt's flat pattern at the
    /// mannequin's waist, the flat tablecloth over the table), not draped: what the
    /// controls name before Drape is pressed. False (and nothing changes) while a
    /// drape runs or when a skirt has no body.
    bool showUndraped(GarmentChoice garment, const library::FabricChoice& fabric);
    bool busy() const { return m_pending; }
    /// Stops the drape; finished(false, "cancelled") follows.
    void cancel();

    /// Results of the last finished drape (valid after finished(true, ...)).
    cloth::SolverStatus lastStatus() const;
    cloth::Positions lastPositions() const;
    GarmentChoice garment() const { return m_garment; }
    QString fabricName() const { return m_fabricName; }
    widget::OrbitCamera& camera() { return controller()->camera(); }

    QSize sizeHint() const override { return {560, 640}; }

signals:
    /// The drape ended: ok = came to rest; otherwise the message says why (or "cancelled").
    void finished(bool ok, const QString& message);

private:
    void setScene(GarmentChoice garment, const library::FabricChoice& fabric);

    std::shared_ptr<const importers::Mannequin> m_mannequin;
    GarmentChoice m_garment = GarmentChoice::Skirt;
    QString m_fabricName;
    bool m_pending = false;
};

QString toString(GarmentChoice g);

} // namespace drape::demo
