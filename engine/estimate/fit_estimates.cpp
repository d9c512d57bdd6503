// What a run knows at its optimum: the uncertainty stage and every parameter's
// estimate, what the priors decided (docs/decisions/0029-priors-from-real-fabrics.md),
// the per-record comparison and the residual analysis.
#include "engine/estimate/detail/pipeline.hpp"
#include "engine/estimate/detail/uncertainty.hpp"

#include "engine/cloth/rest_sensitivity.hpp"
#include "engine/core/error.hpp"

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace drape::estimate::detail {

using cloth::Param;

int sole_variable(const std::vector<FitVariable>& vars, Param q)
{
    for (int i = 0; i < static_cast<int>(vars.size()); ++i)
        if (vars[static_cast<std::size_t>(i)].params.size() == 1 && vars[static_cast<std::size_t>(i)].params.front() == q) return i;
    return -1;
}

int fit_dof(const std::vector<ResidualTerm>& terms, int parameters)
{
    int fitted = 0;
    for (const auto& t : terms) fitted += t.fitted ? 1 : 0;
    return std::max(1, fitted - parameters);
}

int measurement_parameters(const std::vector<MeasuredDrape>& records, const FitOptions& options)
{
    int count = 0;
    const bool contours_fitted = std::find(options.channels.begin(), options.channels.end(), "contours") != options.channels.end();
    for (const auto& r : records) {
        if (!contours_fitted || !(r.untilt_contours || r.recentre_contours)) continue;
        std::vector<double> depths;
        for (const auto& c : r.contours)
            if (c.profile.complete() && std::find(depths.begin(), depths.end(), c.depth_m) == depths.end()) depths.push_back(c.depth_m);
        if (!depths.empty()) count += r.untilt_contours && depths.size() >= 2 ? 4 : 2;
    }
    return count;
}

bool linearised_term(const ResidualTerm& t) { return t.smooth && t.fitted && t.kind != "closure" && std::isfinite(t.whitened()); }

namespace {

std::string fmt_num(double v)
{
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", v);
    return b;
}

/// FitResult::priors: for each prior row of `best`, whether the prior or the
/// records decided its combination of the search coordinates. The posterior
/// information on it (J_opt with the prior rows) less the prior's own is the
/// records' share; where the records' share is below the prior's, the prior
/// decided (it gives more than half the information). The records' sigma is
/// reported as the sigma they alone would give (infinity: they do not see it).
/// The parameters a prior decided get a note in their estimate.
void assess_priors(FitResult& out, const Evaluator& ev, const std::vector<FitVariable>& vars, const Eigen::MatrixXd& J_opt, const Evaluation& best)
{
    const std::size_t R = ev.record_rows();
    if (best.terms.size() <= R || static_cast<std::size_t>(J_opt.rows()) != best.terms.size()) return;
    const int n = static_cast<int>(vars.size());
    const Eigen::MatrixXd F = J_opt.transpose() * J_opt;
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> es(F);
    const double lmax = es.eigenvalues().size() ? es.eigenvalues().maxCoeff() : 0.0;
    const double s2 = std::max(1.0, out.chi2 / std::max(1, out.dof));
    for (std::size_t row = R; row < best.terms.size(); ++row) {
        const ResidualTerm& t = best.terms[row];
        FitResult::PriorUse u;
        u.kind = t.kind;
        u.value = t.simulated;
        u.centre = t.measured;
        u.prior_sigma = t.sigma;
        Eigen::VectorXd a(n);
        for (int i = 0; i < n; ++i) a[i] = ev.prior_slope(t.kind, static_cast<std::size_t>(i));
        if (a.norm() == 0) continue; // a tied bending: no anisotropy to decide
        double v = 0; // posterior variance of the combination [decades^2], before the chi2/dof scaling
        bool unseen = false;
        for (int k = 0; k < n; ++k) {
            const double proj = es.eigenvectors().col(k).dot(a);
            const double l = es.eigenvalues()[k];
            if (l > 1e-8 * lmax && l > 1e-12) v += proj * proj / l;
            else if (std::abs(proj) > 1e-6 * a.norm()) unseen = true;
        }
        if (unseen) continue; // neither the records nor the priors see it: not constrained (the intervals say so)
        const double prior_info = 1.0 / (u.prior_sigma * u.prior_sigma);
        const double data_info = 1.0 / v - prior_info;
        u.data_sigma = data_info > 1e-12 * prior_info ? std::sqrt(s2 / data_info) : std::numeric_limits<double>::infinity();
        u.decided_by_prior = data_info < prior_info;
        if (u.decided_by_prior)
            for (auto& e : out.estimates) {
                const bool bend = e.id == Param::BendWarp || e.id == Param::BendWeft;
                if (!bend || e.role != "fitted") continue;
                char b[240];
                std::snprintf(b, sizeof b, "%s is the prior's, not the data's (the records alone: +-%s decades, the prior +-%.2f)",
                              t.kind == "prior_anisotropy" ? "the warp/weft ratio" : "the bending level",
                              std::isfinite(u.data_sigma) ? fmt_num(u.data_sigma).c_str() : "inf", u.prior_sigma);
                e.note += (e.note.empty() ? "" : "; ") + std::string(b);
            }
        out.priors.push_back(u);
    }
}

/// The uncertainty stage: the 1-sigma of each search coordinate at the optimum
/// (infinite where not taken) into out.covariance and out.correlation, and the
/// whitened exact Jacobian there (Levenberg-Marquardt only; empty otherwise).
std::vector<double> coordinate_uncertainty(FitResult& out, Evaluator& ev, const FitOptions& options, const Eigen::VectorXd& x,
                                           const Evaluation& best, bool search_cancelled, Eigen::MatrixXd& J_opt)
{
    const auto& vars = out.variables;
    const int n = static_cast<int>(vars.size());
    const bool lm = options.method == FitMethod::Sensitivity;
    out.covariance = Eigen::MatrixXd::Constant(n, n, std::numeric_limits<double>::quiet_NaN());
    out.correlation = out.covariance;
    std::vector<double> sigma(static_cast<std::size_t>(n), std::numeric_limits<double>::infinity());
    if (options.uncertainty && !search_cancelled) {
        try {
            if (lm) {
                // The exact Jacobian at the optimum, whitened with the spread-calibrated sigmas.
                J_opt = ev.jacobian(x, best);
                // (A held shear's column stays: the others' intervals carry what not knowing
                // it costs them - conditioned on the typical value they came out too narrow
                // for the synthetic round trip's truth.)
                sigma = sigmas_from_jacobian(J_opt, out);
            } else {
                sigma = coordinate_sigmas(ev, vars, x, best, out);
            }
        } catch (const CancelledFit&) {
            out.cancelled = true;
        }
    }
    return sigma;
}

/// The lever of the overhang's weight on the rim, (R^2 - a^2) / (2 a): the longest of the records'.
double rim_lever_m(const std::vector<MeasuredDrape>& records)
{
    double rim_lever = 0;
    for (const auto& rec : records) {
        const double R = rec.sample_diameter / 2, a = rec.disc_diameter / 2;
        if (a > 0 && R > a) rim_lever = std::max(rim_lever, (R * R - a * a) / (2 * a));
    }
    return rim_lever;
}

/// Record rf's D change for +10 % of each fitted parameter at the optimum: one
/// factorisation of its first seed's rest state's Hessian, no further drape; none
/// when that state is not a stable rest state.
void add_d_drape_sensitivities(RecordFit& rf, const FitResult& out, const MeasuredDrape& record, const FitOptions& options)
{
    try {
        const cloth::FabricParams pr = params_for_record(out.params, record);
        std::vector<Param> ps;
        for (const auto& v : out.variables)
            for (Param q : v.params)
                if (pr[q] != 0) ps.push_back(q);
        for (const auto& s : cloth::drape_metric_sensitivities(cloth::Material(pr), rf.setup, rf.simulations.front().x, ps,
                                                               options.model_options))
            rf.d_drape_per_10_percent.emplace_back(s.param, s.d_drape_coefficient_percent * 0.1 * s.value);
    } catch (const drape::Error&) {
        rf.d_drape_per_10_percent.clear(); // not a stable rest state: no sensitivity reported
    }
}

} // namespace

Eigen::MatrixXd estimate_parameters(FitResult& out, Evaluator& ev, const std::vector<MeasuredDrape>& records, const FitOptions& options,
                                    const Eigen::VectorXd& x, const Evaluation& best, bool search_cancelled)
{
    const auto& vars = out.variables;
    Eigen::MatrixXd J_opt; // the exact Jacobian at the optimum (whitened), when taken
    const std::vector<double> sigma = coordinate_uncertainty(out, ev, options, x, best, search_cancelled, J_opt);
    const double rim_lever = rim_lever_m(records);
    // The mesh's spacing: nominal over the overhang (where the folds hang: the
    // bending length's test), and where the cloth bends over the rim (the grid's,
    // or the rings' refined band there: the rim bend's note).
    const cloth::DrapeSetup first = ev.setup_for(0, options.seed, false);
    const double spacing = first.sample_diameter / std::max(1, options.grid - 1);
    const double rim_spacing = spacing * (options.mesh == cloth::DrapeMesh::Rings ? cloth::drapemeter_rim_grading(first).factor : 1.0);
    parameter_estimates(out, vars, x, sigma, options.uncertainty, spacing, rim_lever, rim_spacing);
    if (J_opt.size() > 0) assess_priors(out, ev, vars, J_opt, best);
    mark_held_shear(out);
    if (options.uncertainty && !out.cancelled) {
        assess_anisotropy(out);
        if (J_opt.size() > 0) confirm_anisotropy_by_setups(out, ev, records, J_opt, best);
    }
    return J_opt;
}

void compare_records(FitResult& out, const Evaluator& ev, const std::vector<MeasuredDrape>& records, const FitOptions& options,
                     const Evaluation& best, bool search_cancelled)
{
    const auto& meas = ev.measured();
    for (std::size_t r = 0; r < records.size(); ++r) {
        RecordFit rf;
        rf.measured = records[r];
        rf.measured_features = meas[r];
        rf.simulated_features = best.features[r];
        rf.simulations = best.sims[r];
        rf.setup = ev.setup_for(static_cast<int>(r), options.seed, true);
        rf.branch_folds = ev.branch_of(static_cast<int>(r));
        rf.dc_error_percent = rf.simulated_features.drape_coefficient_percent - rf.measured_features.drape_coefficient_percent;
        rf.node_error = rf.simulated_features.node_count - rf.measured_features.node_count;
        set_preset(rf, rf.simulated_features, rf.simulations, false); // the preset is the optimum until a calibration moves it
        set_from_flat(rf, ev, r);
        if (!search_cancelled && !rf.simulations.empty() && rf.simulations.front().status.converged())
            add_d_drape_sensitivities(rf, out, records[r], options);
        out.records.push_back(std::move(rf));
    }
}

void analyse_optimum(FitResult& out, const Eigen::MatrixXd& J_opt, int parameters)
{
    // The matched filters against the part of each signature the fit cannot
    // absorb: the Jacobian's rows of the linearised terms (as test_effects).
    Eigen::MatrixXd J_fitted;
    if (J_opt.rows() == static_cast<Eigen::Index>(out.residuals.size())) {
        J_fitted = J_opt;
        for (Eigen::Index k = 0; k < J_fitted.rows(); ++k)
            if (!linearised_term(out.residuals[static_cast<std::size_t>(k)])) J_fitted.row(k).setZero();
    }
    out.residual = analyse_residual(out.residuals, parameters, J_fitted);
    out.residual.exceeds_noise_by_residual = out.residual.exceeds_noise;
}

} // namespace drape::estimate::detail
