#include "engine/estimate/detail/uncertainty.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace drape::estimate::detail {

using cloth::Param;

std::vector<double> coordinate_sigmas(Evaluator& ev, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x,
                                      const Evaluation& best, FitResult& out)
{
    const int n = static_cast<int>(vars.size());
    std::vector<int> rows;
    for (int i = 0; i < static_cast<int>(best.terms.size()); ++i)
        if (best.terms[static_cast<std::size_t>(i)].smooth && best.terms[static_cast<std::size_t>(i)].fitted) rows.push_back(i);
    Eigen::MatrixXd J(static_cast<Eigen::Index>(rows.size()), n);
    for (int i = 0; i < n; ++i) {
        const auto& v = vars[static_cast<std::size_t>(i)];
        const double h = v.log_scale ? 0.1 : 0.05 * (v.upper - v.lower);
        Eigen::VectorXd xp = x, xm = x;
        xp[i] = std::min(x[i] + h, v.upper);
        xm[i] = std::max(x[i] - h, v.lower);
        const Evaluation ep = ev.evaluate(xp, Start::Best);
        ev.report(Stage::Uncertainty);
        const Evaluation em = ev.evaluate(xm, Start::Best);
        ev.report(Stage::Uncertainty);
        // Only drapes at rest are drapes of the model: a side that did not come to
        // rest is replaced by the optimum itself (a one-sided difference); with
        // neither side at rest the column stays 0 and the parameter reads as not
        // constrained, which is what such a fit can say about it.
        const Evaluation* up = ep.at_rest() ? &ep : best.at_rest() ? &best : nullptr;
        const Evaluation* dn = em.at_rest() ? &em : best.at_rest() ? &best : nullptr;
        const double xu = ep.at_rest() ? xp[i] : x[i], xd = em.at_rest() ? xm[i] : x[i];
        for (std::size_t r = 0; r < rows.size(); ++r) {
            const auto k = static_cast<std::size_t>(rows[r]);
            J(static_cast<Eigen::Index>(r), i) = up && dn && up != dn && xu != xd && k < up->terms.size() && k < dn->terms.size()
                                                     ? (up->terms[k].whitened() - dn->terms[k].whitened()) / (xu - xd)
                                                     : 0.0;
        }
    }
    return sigmas_from_jacobian(J, out);
}

std::vector<double> sigmas_from_jacobian(const Eigen::MatrixXd& J, FitResult& out)
{
    const int n = static_cast<int>(J.cols());
    std::vector<double> sigma(static_cast<std::size_t>(n), std::numeric_limits<double>::infinity());
    // Linearised least squares: cov = s^2 (J^T J)^-1, with s^2 the reduced
    // chi-square when the fit is worse than the noise (the noise model was then
    // too optimistic; this keeps intervals honest).
    const Eigen::MatrixXd H = J.transpose() * J;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(H);
    const double lmax = std::max(es.eigenvalues().maxCoeff(), 1e-300);
    const double s2 = std::max(1.0, out.chi2 / out.dof);
    Eigen::MatrixXd C = Eigen::MatrixXd::Zero(n, n);
    std::vector<char> null_dir(static_cast<std::size_t>(n), 0);
    for (int k = 0; k < n; ++k) {
        const double l = es.eigenvalues()[k];
        const Eigen::VectorXd v = es.eigenvectors().col(k);
        if (l > 1e-8 * lmax && l > 1e-12) C += v * v.transpose() / l;
        else
            for (int i = 0; i < n; ++i)
                if (std::abs(v[i]) > 0.1) null_dir[static_cast<std::size_t>(i)] = 1; // the data does not see this direction
    }
    C *= s2;
    out.covariance = C;
    for (int i = 0; i < n; ++i)
        sigma[static_cast<std::size_t>(i)] =
            null_dir[static_cast<std::size_t>(i)] ? std::numeric_limits<double>::infinity() : std::sqrt(std::max(C(i, i), 0.0));
    for (int i = 0; i < n; ++i)
        for (int k = 0; k < n; ++k) {
            const double si = sigma[static_cast<std::size_t>(i)], sk = sigma[static_cast<std::size_t>(k)];
            out.correlation(i, k) = (std::isfinite(si) && std::isfinite(sk) && si > 0 && sk > 0) ? C(i, k) / (si * sk)
                                                                                                  : std::numeric_limits<double>::quiet_NaN();
        }
    return sigma;
}

double bound_edge(const FitVariable& v) { return v.log_scale ? 0.05 : 0.01 * (v.upper - v.lower); }

bool at_fit_bound(const FitVariable& v, double c) { return c - v.lower < bound_edge(v) || v.upper - c < bound_edge(v); }

bool interval_reaches_bound(const FitVariable& v, double c, double half)
{
    return !(c - half > v.lower + bound_edge(v) && c + half < v.upper - bound_edge(v));
}

void parameter_estimates(FitResult& out, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x,
                         const std::vector<double>& sigma, bool uncertainty_computed, double mesh_spacing_m,
                         double rim_lever_m, double rim_spacing_m)
{
    const int n = static_cast<int>(vars.size());
    for (const auto& sp : cloth::param_table()) {
        ParamEstimate e;
        e.id = sp.id;
        e.key = std::string(sp.key);
        e.unit = std::string(sp.unit);
        e.value = out.params[sp.id];
        e.lower95 = e.upper95 = e.value;
        int vi = -1;
        for (int i = 0; i < n; ++i)
            for (Param q : vars[static_cast<std::size_t>(i)].params)
                if (q == sp.id) vi = i;
        if (vi >= 0) {
            const FitVariable& v = vars[static_cast<std::size_t>(vi)];
            const double s = sigma[static_cast<std::size_t>(vi)];
            e.role = "fitted";
            e.sigma_coord = s;
            const double half = 1.96 * s;
            const double lo = x[vi] - half, hi = x[vi] + half;
            e.lower95 = v.to_value(std::max(lo, v.lower));
            e.upper95 = v.to_value(std::min(hi, v.upper));
            const double width_limit = v.log_scale ? 1.0 : 0.5 * (v.upper - v.lower);
            const bool wide = !std::isfinite(half) || 2 * half > width_limit;
            const bool at_bound = at_fit_bound(v, x[vi]);
            e.constrained = uncertainty_computed && !wide && !at_bound && !out.cancelled;
            if (!uncertainty_computed) e.note = "uncertainty not computed";
            else if (!std::isfinite(half)) e.note = "not constrained: the drape does not change with it";
            else if (wide) {
                // Open-ended (it runs into a fit bound: the data say nothing on that
                // side) or wide but bounded by the data on both sides - which the shear
                // hold keeps as fitted, so the table must not read as if it were open.
                const bool open = interval_reaches_bound(v, x[vi], half);
                e.note = "not constrained: the 95 % interval spans more than " + std::string(v.log_scale ? "a decade" : "half the range") +
                         (open ? " and runs into the fit bound" : " (bounded by the data on both sides, loosely)");
            }
            else if (at_bound) e.note = "not constrained: at the fit bound";
            // A bending whose bending length (B / (rho_A g))^(1/3) is shorter than the
            // mesh spacing is not resolved by the fit's grid: the coarse mesh's membrane
            // stiffness does part of the bending's work, and the value does not carry
            // over to another grid (docs/decisions/0004-fit-grid-41.md).
            if (sp.id == Param::BendWarp || sp.id == Param::BendWeft) {
                const double rho_g = out.params[Param::AreaDensity] * 9.81;
                const double c = std::cbrt(e.value / std::max(rho_g, 1e-12));
                if (c < mesh_spacing_m) {
                    char buf[200];
                    std::snprintf(buf, sizeof buf, "bending length %.1f mm is below the fit's mesh spacing %.1f mm: grid-bound value", c * 1e3,
                                  mesh_spacing_m * 1e3);
                    e.note = e.note.empty() ? buf : e.note + "; " + buf;
                    out.grid_bound = true;
                }
                // The bend over the pedestal's rim: the overhang hangs on the rim with the
                // tension T = rho_A g (R^2 - a^2) / (2 a) per unit length, and an elastica
                // under T bends over an edge with a radius of about sqrt(B / T). A mesh
                // coarser than that stores too little of that bend's energy and the
                // preset's D moves with the grid by a point or two (docs/decisions/0019-drapemeter-mesh.md:
                // DL-A04's preset, 4.9 / 6.9 mm against 7.5 mm, spread 1.49 over
                // grids 41-81). Said, not refitted: a finer grid costs several times the time.
                if (rim_lever_m > 0) {
                    const double rim = std::sqrt(e.value / std::max(rho_g * rim_lever_m, 1e-12));
                    const double at_rim = rim_spacing_m > 0 ? rim_spacing_m : mesh_spacing_m;
                    if (rim < at_rim) {
                        char buf[240];
                        std::snprintf(buf, sizeof buf,
                                      "bend over the pedestal's rim about %.1f mm, below the fit's mesh spacing %.1f mm: not resolved, D may move with the grid",
                                      rim * 1e3, at_rim * 1e3);
                        e.note = e.note.empty() ? buf : e.note + "; " + buf;
                    }
                }
            }
        } else if (sp.id == Param::AreaDensity || sp.id == Param::Thickness) {
            e.role = "declared";
            e.note = "measured by the lab (meta.json), not fitted";
        } else if (!sp.affects_statics) {
            e.role = "not identifiable";
            e.constrained = false;
            e.note = "a damper: it does not change a rest state, so a drape test cannot tell its value (kept at the start value)";
        } else {
            e.role = "fixed";
            e.note = sp.id == Param::Friction ? "frictionless disc (baseline model)" : "kept at the start value (not fitted by this model)";
        }
        out.estimates.push_back(e);
    }
}

} // namespace drape::estimate::detail
