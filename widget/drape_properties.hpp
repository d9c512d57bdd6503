#pragma once
// The drapemeter view's designable properties and its public signals, listed
// once. DrapeController declares them (Q_PROPERTY, getter, setter, ...Changed
// signal) and stores them in DrapeSettings; DrapeView declares the same
// Q_PROPERTYs and signals and forwards them to its controller. Qt 6's moc expands
// these macros like the compiler does (checked with moc 6.4: the properties and
// signals are in the meta-object, so Designer's property editor, QUiLoader and
// QML see them as hand-written ones).
//
// X(Type, ArgType, name, setter, default). Units: sampleDiameter and
// discDiameter [mm], timeStep [s] (0 = automatic), restSpeed [m/s],
// restResidual relative to the cloth's weight [-]. The choices are enums
// (drape_enums.hpp), so Designer offers drop-downs. docs/widget.md has the table.
#include "widget/drape_enums.hpp"

#include <QColor>
#include <QString>

#define DRAPE_VIEW_PROPERTIES(X)                                                                      \
    /* the fabric: a preset JSON file, a built-in ("seed-table1"), a fabric of the library, a starter */ \
    /* (silk, cotton, wool, denim), or empty for the parameter table's defaults */                      \
    X(QString, const QString&, fabricPreset, setFabricPreset, QString())                               \
    /* the fabric library a name is looked up in; empty = the user's default library */                 \
    X(QString, const QString&, libraryPath, setLibraryPath, QString())                                 \
    X(double, double, sampleDiameter, setSampleDiameter, 300.0)                                        \
    X(double, double, discDiameter, setDiscDiameter, 150.0)                                            \
    X(int, int, gridSize, setGridSize, 40) /* nodes across the specimen */                             \
    /* what drapes: Disc, Square (drapemeter), Skirt (on the body), Tablecloth, GarmentMesh */          \
    X(drape::widget::Drape::ClothShape, drape::widget::Drape::ClothShape, clothShape, setClothShape,    \
      drape::widget::Drape::Disc)                                                                      \
    /* a body mesh file (assimp: OBJ, Collada, glTF, FBX, PLY, STL), drawn and collided with; empty = */ \
    /* none (a Skirt then uses the default mannequin) */                                               \
    X(QString, const QString&, bodyFile, setBodyFile, QString())                                       \
    /* a garment mesh file for clothShape = GarmentMesh (its top boundary is pinned) */                \
    X(QString, const QString&, garmentFile, setGarmentFile, QString())                                 \
    /* Static: the cloth comes to rest (the command line's path, frames shown as it goes); */          \
    /* Symplectic/Implicit/RK4 animate the fall (an explicit one may never settle a stiff cloth) */    \
    X(drape::widget::Drape::Integrator, drape::widget::Drape::Integrator, integrator, setIntegrator,   \
      drape::widget::Drape::Static)                                                                    \
    X(QString, const QString&, texture, setTexture, QString()) /* BMP/PNG/JPEG, empty = plain */       \
    X(bool, bool, running, setRunning, false)                                                          \
    X(double, double, timeStep, setTimeStep, 0.0)                                                      \
    X(double, double, restSpeed, setRestSpeed, 1e-3)                                                   \
    X(double, double, restResidual, setRestResidual, 1e-3)                                             \
    X(drape::widget::Drape::ViewPreset, drape::widget::Drape::ViewPreset, viewPreset, setViewPreset,    \
      drape::widget::Drape::Iso)                                                                       \
    X(QColor, const QColor&, clothColor, setClothColor, (QColor(0xb0, 0x3a, 0x48)))                   \
    X(QColor, const QColor&, backgroundColor, setBackgroundColor, (QColor(0x2b, 0x2f, 0x36)))         \
    X(bool, bool, showColliders, setShowColliders, true)                                               \
    X(bool, bool, showOutlines, setShowOutlines, false)                                                \
    X(bool, bool, pickEnabled, setPickEnabled, true)                                                   \
    /* the lab's four calibration chessboards on the floor (drape-lab README) */                       \
    X(bool, bool, labFloor, setLabFloor, true)

/// Signals DrapeView forwards from its controller besides the ...Changed ones:
/// X(name, (parameters)).
#define DRAPE_VIEW_SIGNALS(X)                                                                         \
    /* with every frame shown: simulated time [s], fastest free vertex [m/s] */                       \
    X(progress, (double simulatedTime, double maxSpeed))                                               \
    /* the cloth came to rest (speed and residual below restSpeed / restResidual) */                  \
    X(restReached, ())                                                                                 \
    /* bad input or engine trouble, as a readable message; the view stays usable */                   \
    X(errorOccurred, (const QString& message))                                                         \
    X(resultsSaved, (const QString& jsonPath, const QString& objPath))                                 \
    X(jobProgress, (double fraction, const QString& message))                                          \
    X(jobFinished, (bool ok, const QString& message))                                                  \
    /* a drape to rest (drapeToRest, or the Static integrator): fraction in [0, 1] (the residual's */ \
    /* way down to restResidual on a log scale; negative = unknown) and a status line */              \
    X(drapeProgress, (double fraction, const QString& status))                                         \
    /* results of the rest state are ready (positions(), drapeCoefficient, results()) */               \
    X(resultsReady, ())

// ---- expansions used by DrapeController and DrapeView --------------------------

#define DRAPE_DECLARE_Q_PROPERTY(Type, Arg, name, setter, init) \
    Q_PROPERTY(Type name READ name WRITE setter NOTIFY name##Changed)
#define DRAPE_DECLARE_CHANGED_SIGNAL(Type, Arg, name, setter, init) void name##Changed(Arg value);
#define DRAPE_DECLARE_SIGNAL(name, params) void name params;

namespace drape::widget {

/// The designable state, with its defaults.
struct DrapeSettings {
#define DRAPE_SETTINGS_MEMBER(Type, Arg, name, setter, init) Type name = init;
    DRAPE_VIEW_PROPERTIES(DRAPE_SETTINGS_MEMBER)
#undef DRAPE_SETTINGS_MEMBER
};

} // namespace drape::widget
