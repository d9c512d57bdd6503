#pragma once
// The widget's data file: `name.json` (format "drapekit-widget-state": preset,
// set-up, solver, state and the engine's drape metrics) and `name.obj` (the
// engine's OBJ writer: world positions [m], texture coordinates, triangles).
#include "widget/drape_setup.hpp"

#include "engine/cloth/system.hpp"

#include <QString>

#include <vector>

namespace drape::widget {

/// How the state was reached (for the JSON's solver and state blocks).
struct SolverSettings {
    QString integrator;      ///< as the user named it
    double timeStep = 0;     ///< [s] in use
    double restSpeed = 0;    ///< [m/s]
    double restResidual = 0; ///< relative
    long steps = 0;          ///< taken since the last build or reset
};

/// Writes both files atomically and returns the OBJ's path. Throws on I/O errors.
QString saveDrapeResults(const QString& jsonPath, const cloth::ClothSystem& sys, const DrapeSpec& spec,
                         const SolverSettings& solver, const std::vector<float>& texcoord);

} // namespace drape::widget
