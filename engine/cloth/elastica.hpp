#pragma once
// The heavy elastica: a strip clamped level at one end, bending under its own
// weight (bending rigidity B per width [N*m], weight w per area [N/m^2], length L).
// An analytic reference for the engine's bending (a cantilever), and the
// free-strip bound of a drape: each radial line of a drapemeter's overhang,
// taken alone, is such a strip clamped at the pedestal's rim; a drape is an
// annulus that must fold or shorten around its circumference to fall, which its
// strips need not, so a drape of linear bending B lies at or above the drape
// coefficient of its free strips (checked on the engine's drapes in tst_physics).
// Read backwards, a measured D gives the largest linear bending that can drape
// to it at that set-up.

namespace drape::cloth {

/// The strip's tip, in units of its length L, for lambda = w L^3 / B.
struct ElasticaTip {
    double reach = 1; ///< horizontal distance of the tip from the clamp / L
    double drop = 0;  ///< how far the tip hangs below the clamp / L
    bool converged = false;
};

/// The heavy elastica theta'' = -lambda (1 - s) cos(theta), theta(0) = 0,
/// theta'(1) = 0, as a chain of `segments` straight pieces at rest (Newton on
/// the energy, one tridiagonal solve per step). Throws ParameterError for
/// lambda < 0 or not finite, or segments < 4.
ElasticaTip heavy_elastica(double lambda, int segments = 400);

/// Drape coefficient [%] of an overhang made of free strips: specimen and disc
/// diameters [m], areal density [kg/m^2], bending rigidity [N*m], gravity [m/s^2].
double free_strip_drape_coefficient(double sample_diameter, double disc_diameter, double areal_density,
                                    double bending, double gravity = 9.81);

/// The bending rigidity [N*m] whose free strips drape to `dc_percent` at that
/// set-up: the largest linear bending a drape to that D can have. Throws
/// ParameterError when dc_percent is not in (0, 100) or the set-up is not one.
double free_strip_bending_bound(double sample_diameter, double disc_diameter, double areal_density,
                                double dc_percent, double gravity = 9.81);

} // namespace drape::cloth
