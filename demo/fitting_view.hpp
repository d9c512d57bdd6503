#pragma once
// FittingView: one 3-D view of a fitting - the widget library's SceneWidget,
// filled with the floor, the mannequin or the round table, and the garment that
// importers::make_skirt_scene / make_tablecloth_scene build. The drape runs in
// the library's RestJob (the static solver on a worker thread, frames shown as
// it goes, cancel), so the window stays live.
#include "engine/library/fabric_choices.hpp"
#include "importers/garment_scene.hpp"

#include "widget/orbit_camera.hpp"
#include "widget/rest_job.hpp"
#include "widget/scene_widget.hpp"

#include <QColor>

#include <memory>

namespace drape::demo {

class FittingView : public widget::SceneWidget {
    Q_OBJECT
public:
    explicit FittingView(QWidget* parent = nullptr);
    ~FittingView() override;

    /// Shows this body (null hides it). Takes effect for the next skirt drape.
    void setMannequin(std::shared_ptr<const importers::Mannequin> m);
    std::shared_ptr<const importers::Mannequin> mannequin() const { return m_mannequin; }
    /// Builds the garment scene on the GUI thread (fast) and drapes it on a
    /// worker thread. Returns false with `error` set when the scene cannot be
    /// built (bad fabric, no mannequin) or a drape is already running.
    bool drape(importers::Garment garment, const library::FabricChoice& fabric, QString* error = nullptr);
    void cancel() { m_job.cancel(); }
    bool busy() const { return m_job.running(); }

    void setClothColor(const QColor& c);
    /// Frames the camera on the current garment (body or table).
    void resetCamera();
    widget::OrbitCamera& camera();

    /// Results of the last finished drape (valid after finished(true, ...)).
    const cloth::SolverStatus& lastStatus() const { return m_job.status(); }
    cloth::Positions lastPositions() const;
    /// The garment scene of the last drape (null before the first).
    const importers::Scene* garmentScene() const { return m_garment.get(); }
    QString fabricName() const { return m_fabricName; }

    QSize sizeHint() const override { return {560, 640}; }

signals:
    /// fraction in [0, 1], or negative when unknown.
    void progress(double fraction, const QString& message);
    void finished(bool ok, const QString& message);

private:
    void showBody();
    bool tablecloth() const { return m_garment && m_garment->garment == importers::Garment::Tablecloth; }

    std::shared_ptr<const importers::Mannequin> m_mannequin;
    std::unique_ptr<importers::Scene> m_garment;
    QString m_fabricName;
    QColor m_clothColor{0xb0, 0x3a, 0x48};
    widget::RestJob m_job; ///< last: joined before the garment scene it solves goes
};

} // namespace drape::demo
