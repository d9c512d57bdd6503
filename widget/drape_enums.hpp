#pragma once
// The drape view's choices as enums: Qt Designer shows them as drop-downs, uic
// writes them as C++ constants (drape::widget::Drape::Static), QML reads them as
// Drape.Static. One namespace, plain (unscoped) enums as Qt's own (Qt::AlignLeft),
// so every value is unique across the three.
#include "widget/drape_widget_export.hpp"

#include "engine/cloth/solver.hpp"

#include <QObject>
#include <QString>
#include <QtQml/qqmlregistration.h>

#include <optional>

namespace drape {
namespace widget {
namespace Drape {
Q_NAMESPACE_EXPORT(DRAPE_WIDGET_EXPORT)
QML_ELEMENT

/// The time integrator, or the rest-state solver (Static).
enum Integrator {
    Symplectic, ///< semi-implicit Euler: cheap steps, a small cloth drapes live
    Euler,      ///< explicit Euler
    Midpoint,
    RK4,
    Implicit,   ///< implicit Euler: large or stiff cloths
    Static      ///< Newton's method on the rest state (what `drape simulate` uses)
};
Q_ENUM_NS(Integrator)

/// Camera: the lab's three stations, a closer iso view, or wherever the user orbited to.
enum ViewPreset { Top, Side, Iso, Close, Free };
Q_ENUM_NS(ViewPreset)

/// What drapes: the drapemeter specimen (Disc) or a square sheet on the pedestal;
/// the built-in circle skirt on the body; a round tablecloth on a round table; or
/// the garment mesh a host gave (DrapeController::setGarmentMesh / garmentFile).
enum ClothShape { Disc, Square, Skirt, Tablecloth, GarmentMesh };
Q_ENUM_NS(ClothShape)

} // namespace Drape

/// The engine's integrator for an enum value.
DRAPE_WIDGET_EXPORT cloth::Integrator toEngine(Drape::Integrator i);
/// Lower-case names as the command line writes them ("symplectic", "static",
/// "top", "disc", "skirt", ...), and back (nullopt for an unknown name).
DRAPE_WIDGET_EXPORT QString toString(Drape::Integrator i);
DRAPE_WIDGET_EXPORT QString toString(Drape::ViewPreset v);
DRAPE_WIDGET_EXPORT QString toString(Drape::ClothShape s);
DRAPE_WIDGET_EXPORT std::optional<Drape::Integrator> parseIntegrator(const QString& name);
DRAPE_WIDGET_EXPORT std::optional<Drape::ViewPreset> parseViewPreset(const QString& name);
DRAPE_WIDGET_EXPORT std::optional<Drape::ClothShape> parseClothShape(const QString& name);
/// True for the drapemeter shapes (Disc, Square): the pedestal, the lab floor, the drape coefficient.
inline bool isDrapemeter(Drape::ClothShape s) { return s == Drape::Disc || s == Drape::Square; }

} // namespace widget
} // namespace drape
