#pragma once
// The side view: the hem traced against the pedestal, in the world frame.
#include <Eigen/Core>

#include <cmath>
#include <string>
#include <vector>

namespace drape::capture {

struct SideView {
    bool measured = false;
    int columns = 0;                      ///< columns where the hem was found in front of the pedestal
    double hem_min_z = std::nan("");      ///< lowest hem point seen in front of the pedestal [m]
    double hem_min_theta = std::nan("");  ///< its angle [rad]
    double model_rms_diff = std::nan(""); ///< RMS(side z - top height model z) at those points [m]
    std::vector<Eigen::Vector2d> hem_px;  ///< the traced hem in the side image [px]
    std::vector<Eigen::Vector3d> hem_world; ///< the same in the world [m]
    std::vector<std::string> warnings;
};

} // namespace drape::capture
