#pragma once
// The side view: the hem traced against the pedestal, in the world frame.
#include <Eigen/Core>

#include <cmath>
#include <string>
#include <vector>

namespace drape::capture {

/// The pedestal's diameter from its silhouette in the side photo, on rows below
/// where any cloth hangs: a check of the declared D2 that neither the top
/// photo's scale nor a fit can give (a wrong pedestal looks like a camera scale).
struct PedestalWidth {
    bool measured = false;
    double diameter = std::nan("");       ///< [m]
    double diameter_sigma = std::nan(""); ///< its standard uncertainty [m]
    double declared = std::nan("");       ///< meta.json's support_disc_diameter_D2 [m]
    int rows = 0;                         ///< image rows both silhouette edges were found on (after outliers)
    bool differs = false;                 ///< beyond 3 sigma and 1.5 mm from the declared diameter
};

struct SideView {
    bool measured = false;
    int columns = 0;                      ///< columns where the hem was found in front of the pedestal
    double hem_min_z = std::nan("");      ///< lowest hem point seen in front of the pedestal [m]
    double hem_min_theta = std::nan("");  ///< its angle [rad]
    double model_rms_diff = std::nan(""); ///< RMS(side z - top height model z) at those points [m]
    std::vector<Eigen::Vector2d> hem_px;  ///< the traced hem in the side image [px]
    std::vector<Eigen::Vector3d> hem_world; ///< the same in the world [m]
    std::vector<std::string> warnings;
    PedestalWidth pedestal; ///< measured whenever the side photo is read, with or without the top view
};

} // namespace drape::capture
