// The effect tests (docs/decisions/0006-effect-tests.md): the candidate effects
// tested against the residual at the kept optimum.
#include "engine/estimate/detail/pipeline.hpp"

#include "engine/core/error.hpp"

#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drape::estimate::detail {

void test_effects(Evaluator& ev, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x, const Evaluation& best,
                  Eigen::MatrixXd J, FitResult& out)
{
    const int n = static_cast<int>(vars.size());
    ev.announce(Stage::Effects); // (the Jacobian below, when the fit took none, is theirs)
    if (J.rows() != static_cast<Eigen::Index>(best.terms.size())) J = ev.jacobian(x, best);
    std::vector<EffectSignature> sigs;
    try {
        sigs = ev.effect_signatures(x, best);
    } catch (const drape::Error& e) {
        // Not a stable rest state (the Hessian is not positive definite): no
        // linearisation, so no test; the report says so.
        out.residual.unexplained = std::string("candidate effects not tested: ") + e.what();
        return;
    }
    // The test's rows: the linearised terms, each in its channel (every channel an
    // effect reaches must be explained by its refit, not traded against another:
    // docs/model-discrepancy.md, "How an effect is named").
    Eigen::VectorXd r = Eigen::VectorXd::Zero(J.rows());
    std::vector<int> channel(static_cast<std::size_t>(J.rows()), -1);
    int rows = 0;
    for (Eigen::Index k = 0; k < J.rows(); ++k) {
        const auto& t = best.terms[static_cast<std::size_t>(k)];
        if (linearised_term(t)) {
            r[k] = t.whitened();
            ++rows;
            channel[static_cast<std::size_t>(k)] = t.kind == "dc" || t.kind == "hem"                 ? 0
                                                   : t.kind.rfind("prior", 0) == 0 || t.kind == "nodes" ? -1
                                                                                                        : 1;
        } else {
            J.row(k).setZero();
        }
    }
    // A fit worse than its noise model (chi2 / dof > 1) scales every delta chi2
    // up by that factor: the tests divide by it, as the intervals do.
    const double s2 = std::max(1.0, out.chi2 / std::max(1, out.dof));
    auto cands = test_candidates(J, r, sigs, rows, s2, channel);
    // Verify the strongest parameter effect beyond noise with a drape: the joint
    // Gauss-Newton step (fitted coordinates and the effect), warm from the optimum.
    int top = -1;
    for (int k = 0; k < static_cast<int>(cands.size()); ++k)
        if (cands[static_cast<std::size_t>(k)].verdict == "beyond noise" && (top < 0 || cands[static_cast<std::size_t>(k)].delta_chi2 > cands[static_cast<std::size_t>(top)].delta_chi2))
            top = k;
    // (The declared weight and thickness come from the record in every drape of
    // the fit, so they cannot be verified this way.)
    bool declared = false;
    if (top >= 0)
        for (cloth::Param q : sigs[static_cast<std::size_t>(top)].spec->params)
            declared = declared || q == cloth::Param::AreaDensity || q == cloth::Param::Thickness;
    if (top >= 0 && !declared && sigs[static_cast<std::size_t>(top)].spec->kind == EffectKind::Parameter) {
        const auto& sig = sigs[static_cast<std::size_t>(top)];
        Eigen::MatrixXd A(J.rows(), n + 1);
        A << J, sig.columns;
        Eigen::VectorXd step = A.colPivHouseholderQr().solve(-r);
        Eigen::VectorXd xn = x;
        for (int i = 0; i < n; ++i) {
            const auto& v = vars[static_cast<std::size_t>(i)];
            const double cap = v.log_scale ? 0.5 : 0.1 * (v.upper - v.lower);
            xn[i] = std::clamp(x[i] + std::clamp(step[i], -cap, cap), v.lower, v.upper);
        }
        cloth::FabricParams p = ev.params_at(xn);
        const double a = std::clamp(step[n], -std::log(3.0), std::log(3.0)); // d ln p, at most a factor 3
        for (std::size_t j = 0; j < sig.spec->params.size(); ++j) {
            const cloth::Param q = sig.spec->params[j];
            p[q] = std::clamp(p[q] * std::exp(effect_weight(*sig.spec, j) * a), cloth::spec(q).lower, cloth::spec(q).upper);
        }
        const Evaluation v = ev.evaluate_params(p, Start::Best);
        ev.report(Stage::Effects);
        if (v.at_rest()) // a drape not at rest verifies nothing
            cands[static_cast<std::size_t>(top)].verified_delta_chi2 = (best.chi2 - v.chi2) / s2; // on the scale of the test
    }
    // A held shear: in the free fit it is still a column (its intervals keep it), so
    // the library's shear test reads "fitted already" - what freeing it would buy is
    // the hold's own likelihood ratio; in a tied refit it is no coordinate and the
    // test ran, from the held value. Either way the candidate says it is held.
    if (out.shear_hold.held)
        for (auto& c : cands)
            if (c.name == "shear_stiffness") {
                char buf[300];
                std::snprintf(buf, sizeof buf,
                              "held at the typical value %.4g N/m (open-ended when fitted); holding it moved chi2 by %+.2f "
                              "(scaled, the search's sigmas; the report's Shear line)",
                              out.shear_hold.held_N_m, out.shear_hold.delta_chi2);
                if (c.verdict == "not testable" && c.note.rfind("the model fits it already", 0) == 0) c.note = buf;
                else c.note = std::string(buf) + (c.note.empty() ? "" : "; " + c.note);
            }
    out.residual.candidates = cands;
    // A candidate beyond noise is a structured residual even when the total
    // chi2 is not large (as the matched filters of analyse_residual).
    for (const auto& c : cands)
        if (c.verdict == "beyond noise") {
            out.residual.exceeds_noise = true;
            char buf[200];
            std::snprintf(buf, sizeof buf, "candidate %s: delta chi2 %.1f for %d parameter(s)", c.name.c_str(), c.delta_chi2, c.parameters);
            out.residual.exceeds_because.push_back(buf);
        }
    out.residual.named_effect = name_effect(cands, out.chi2, out.dof);
    if (out.residual.exceeds_noise && out.residual.named_effect.empty()) {
        std::string where;
        double worst = 0;
        for (const auto& [k, v] : out.residual.kind_rms)
            if (v > worst) worst = v, where = k;
        char buf[200];
        std::snprintf(buf, sizeof buf, "unexplained: largest in channel %s (whitened RMS %.1f)", where.c_str(), worst);
        out.residual.unexplained = buf;
        if (!out.residual.dominant_harmonics.empty())
            out.residual.unexplained += ", harmonic " + std::to_string(out.residual.dominant_harmonics.front());
    }
}

} // namespace drape::estimate::detail
