#pragma once
// Small pieces the integrators and the static solvers share. Internal to engine/cloth.
#include "engine/cloth/solver.hpp"

#include <Eigen/Core>

namespace drape::cloth::detail {

inline Eigen::Map<Eigen::VectorXd> flat(Positions& P) { return {P.data(), P.size()}; }
inline Eigen::Map<const Eigen::VectorXd> flat(const Positions& P) { return {P.data(), P.size()}; }

inline void mask_pinned(const ClothSystem& s, Positions& f)
{
    for (int i = 0; i < s.vertex_count(); ++i)
        if (s.pinned(i)) f.row(i).setZero();
}

/// |weight| of the free vertices [N] (1 when there is none): the residual's scale.
inline double weight_norm(const ClothSystem& s)
{
    const Positions g = s.gravity_forces();
    const double w = flat(g).norm();
    return w > 0 ? w : 1.0;
}

/// The static solver (static_solver.cpp).
SolverStatus run_static(ClothSystem& s, const RestOptions& opt);

} // namespace drape::cloth::detail
