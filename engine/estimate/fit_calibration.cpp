// The flat calibration (FitOptions::flat_calibration,
// docs/decisions/0020-flat-calibration.md): the preset moved until, draped from
// flat, it gives the records' D - or their fold count (fit_calibration_folds.cpp) -
// then draped as the fit drapes it.
#include "engine/estimate/detail/flat_calibration.hpp"
#include "engine/estimate/detail/pipeline.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

namespace drape::estimate::detail {

using cloth::Param;

namespace {

std::string fmt_chi2(double d)
{
    char b[64];
    std::snprintf(b, sizeof b, "%+.1f (linearised)", d);
    return b;
}

/// Record r's mean D error from flat (the fit grid's seeds and the finer grid's
/// drape at rest, each drape one vote) and the largest fold-count error of any
/// one of those drapes (and, given the pointers, adds each drape's signed
/// fold-count error and counts the drapes); false when the record has no drape from flat on its fold
/// branch (a record fitted from the random mix keeps the spread stage's drapes of
/// the optimum, which draw_from_flat does not redraw) or no measured D.
bool flat_error(const Evaluator& ev, const RecordFit& rf, std::size_t r, double& d_error, double& fold_error, double* signed_fold_sum = nullptr,
                int* fold_drapes = nullptr)
{
    const double dm = rf.measured_features.drape_coefficient_percent, nm = rf.measured_features.node_count;
    if (ev.branch_of(static_cast<int>(r)) == 0 || !std::isfinite(dm)) return false;
    double sum = 0;
    int n = 0;
    fold_error = 0;
    // One drape's fold-count error: the worst, and the signed sum for the caller.
    auto fold = [&](double err) {
        fold_error = std::max(fold_error, std::abs(err));
        if (signed_fold_sum) *signed_fold_sum += err;
        if (fold_drapes) ++*fold_drapes;
    };
    if (r < ev.cold_features().size() && ev.cold_seeds(r) > 0) {
        const int s = ev.cold_seeds(r);
        sum += s * ev.cold_features()[r].drape_coefficient_percent;
        n += s;
        if (std::isfinite(nm))
            for (double k : ev.cold_node_counts(r)) fold(k - nm);
    }
    if (const Evaluator::FineDrape* f = ev.cold_fine(r); f && f->at_rest) {
        sum += f->features.drape_coefficient_percent;
        ++n;
        if (std::isfinite(nm)) fold(f->features.node_count - nm);
    }
    if (n == 0 || !std::isfinite(sum)) return false;
    d_error = sum / n - dm;
    return true;
}

} // namespace

FlatCalibrator::FlatCalibrator(Evaluator& evaluator, const std::vector<FitVariable>& variables, const Eigen::VectorXd& optimum,
                               const Eigen::MatrixXd& jacobian, FitResult& result)
    : ev(evaluator), vars(variables), x(optimum), J_opt(jacobian), kept(result), c(result.flat_calibration)
{
    c = {};
    c.bend_warp_fitted = kept.params[Param::BendWarp];
    c.bend_weft_fitted = kept.params[Param::BendWeft];
    c.chi2_increase = std::numeric_limits<double>::quiet_NaN();
    R = kept.records.size();
}

int FlatCalibrator::measure(double& e, double& folds, std::vector<char>* records_used, double* signed_folds) const
{
    double sum = 0, fsum = 0;
    int n = 0, nf = 0;
    folds = 0;
    if (records_used) records_used->assign(R, 0);
    for (std::size_t r = 0; r < R; ++r) {
        double de = 0, fe = 0, fs = 0;
        int fn = 0;
        if (!flat_error(ev, kept.records[r], r, de, fe, &fs, &fn)) continue;
        sum += de;
        folds = std::max(folds, fe);
        fsum += fs;
        nf += fn;
        ++n;
        if (records_used) (*records_used)[r] = 1;
    }
    e = n ? sum / n : std::numeric_limits<double>::quiet_NaN();
    if (signed_folds) *signed_folds = nf ? fsum / nf : 0.0;
    return n;
}

bool FlatCalibrator::is_bend(int i) const { return std::find(bend.begin(), bend.end(), i) != bend.end(); }

double FlatCalibrator::score(double e, double folds) const
{
    return (e / c.tolerance) * (e / c.tolerance) + (folds / node_sigma) * (folds / node_sigma);
}

void FlatCalibrator::keep(const Eigen::VectorXd& xs, double e, double folds)
{
    best_score = score(e, folds);
    best_e = e;
    best_folds = folds;
    best_x = xs;
    best_records = kept.records;
    for (std::size_t r = 0; r < R; ++r) set_from_flat(best_records[r], ev, r);
}

double FlatCalibrator::lin_cost(const Eigen::VectorXd& dx) const
{
    if (!have_J) return std::numeric_limits<double>::quiet_NaN();
    Eigen::VectorXd dr = J_opt * dx;
    double d2 = 0;
    for (Eigen::Index k = 0; k < dr.size(); ++k)
        if (linearised_term(kept.residuals[static_cast<std::size_t>(k)])) {
            const double w = kept.residuals[static_cast<std::size_t>(k)].whitened();
            d2 += (w + dr[k]) * (w + dr[k]) - w * w;
        }
    return d2;
}

bool FlatCalibrator::scaled(const Eigen::VectorXd& from, double ln_s, Eigen::VectorXd& xs) const
{
    xs = from;
    for (int i : bend) {
        const FitVariable& v = vars[static_cast<std::size_t>(i)];
        xs[i] = std::clamp(from[i] + ln_s / std::log(10.0), v.lower, v.upper);
    }
    const cloth::FabricParams ps = ev.params_at(xs), pf = ev.params_at(from);
    return std::abs(ps[Param::BendWarp] / ps[Param::BendWeft] / ratio0 - 1) <= 1e-9 &&
           std::abs(std::log(ps[Param::BendWarp] / pf[Param::BendWarp])) >= 1e-6;
}

double FlatCalibrator::bend_scale(const Eigen::VectorXd& xs) const { return ev.params_at(xs)[Param::BendWarp] / c.bend_warp_fitted; }

bool FlatCalibrator::needs_calibration()
{
    n_used = measure(e0, folds0, &used, &signed0);
    char buf[700];
    if (n_used == 0) {
        c.reason = "no drape from flat on a record's fold branch with a measured D: not calibrated";
        return false;
    }
    c.tried = true;
    c.error_before = c.error_after = e0;
    c.fold_error_before = c.fold_error_after = folds0;
    over = n_used > 1 ? " (mean over " + std::to_string(n_used) + " records)" : std::string();
    double sigma = 0;
    int nd = 0;
    for (const auto& t : kept.residuals)
        if (t.kind == "dc" && t.fitted && std::isfinite(t.sigma)) sigma += t.sigma, ++nd;
    c.tolerance = nd ? sigma / nd : 1.0;
    if (folds0 <= 1 && std::abs(e0) <= c.tolerance) {
        std::snprintf(buf, sizeof buf, "draped from flat the preset gives the record's D within the D channel's sigma (%+.1f against %.1f points%s): kept as fitted",
                      e0, c.tolerance, over.c_str());
        c.reason = buf;
        return false;
    }
    return true;
}

bool FlatCalibrator::bendings_scalable()
{
    bool linear = false;
    for (int i = 0; i < static_cast<int>(vars.size()); ++i) {
        const auto& ps = vars[static_cast<std::size_t>(i)].params;
        if (std::find(ps.begin(), ps.end(), Param::BendWarp) != ps.end() || std::find(ps.begin(), ps.end(), Param::BendWeft) != ps.end()) {
            bend.push_back(i);
            linear = linear || !vars[static_cast<std::size_t>(i)].log_scale;
        }
    }
    miss = folds0 > 1 ? "lays a fold count " + std::to_string(static_cast<int>(std::lround(folds0))) + " off the record's" : "misses the record's D";
    if (bend.empty() || linear) {
        char buf[700];
        std::snprintf(buf, sizeof buf, "draped from flat the preset %s (D %+.1f points%s), but the bendings are %s: not calibrated", miss.c_str(), e0,
                      over.c_str(), bend.empty() ? "not fitted" : "not fitted on a log scale");
        c.reason = buf;
        return false;
    }
    return true;
}

void FlatCalibrator::prepare_steps()
{
    node_sigma = ev.options().noise.nodes > 0 ? ev.options().noise.nodes : 0.75;
    ratio0 = c.bend_warp_fitted / c.bend_weft_fitted;
    best_score = score(e0, folds0);
    best_e = e0;
    best_folds = folds0;
    best_x = x;
    have_J = J_opt.rows() == static_cast<Eigen::Index>(kept.residuals.size()) && J_opt.cols() == x.size();
    s2 = std::max(1.0, kept.chi2 / std::max(1, kept.dof));
    // dD / d ln(scale) from the exact sensitivities at the optimum (first seed's
    // rest state), over the records measured above.
    slope = 0;
    int ns = 0;
    for (std::size_t r = 0; r < R; ++r) {
        if (!used[r]) continue;
        double s10 = 0;
        bool have = false;
        for (const auto& [q, d] : kept.records[r].d_drape_per_10_percent)
            if (q == Param::BendWarp || q == Param::BendWeft) s10 += d, have = true;
        if (have) slope += s10 / std::log(1.1), ++ns;
    }
    slope_ok = ns > 0 && slope / ns > 0;
    if (slope_ok) slope /= ns;
    max_step = std::log(1.5);
    // Whether the drapes from flat include the finer grid's (Evaluator::draw_from_flat).
    finer = ev.options().flat_check_grid > ev.options().grid && ev.options().random_start_seeds > 0;
}

void FlatCalibrator::scale_for_d()
{
    double ln_s = std::clamp(-e0 / slope, -max_step, max_step);
    double prev_ln = 0, prev_e = e0;
    for (int step = 0; step < 2; ++step) {
        Eigen::VectorXd xs;
        if (!scaled(x, ln_s, xs)) break;
        const double scale = bend_scale(xs);
        ev.draw_from_flat(xs, Stage::FromFlatCalibrated);
        ++c.steps;
        double e = 0, folds = 0;
        if (measure(e, folds, nullptr) != n_used) break;
        c.history.push_back({scale, e, folds, "D", 0, lin_cost(xs - x), finer});
        // Kept when its drapes are closer to the record, the fold count within 1.
        if (folds <= 1 && score(e, folds) < best_score) keep(xs, e, folds);
        // Done within the D channel's sigma: D from flat scatters with the fold
        // pattern (one preset's drapes from flat differ by 2-3 points between seeds),
        // so aiming closer draws again on noise (DL-A04: a secant step from +1.0
        // landed at -1.5 with half a fold off).
        if (std::abs(e) <= c.tolerance || folds > 1) break;
        // Secant through the last two points (the sensitivity at the optimum is
        // the fitted branch's; the drapes from flat may rest on another).
        const double ln_now = std::log(scale);
        const double sec = (e - prev_e) / (ln_now - prev_ln);
        if (!(sec > 0)) break;
        prev_ln = ln_now;
        prev_e = e;
        ln_s = std::clamp(ln_now - e / sec, -max_step, max_step);
    }
}

namespace {

/// Moves every fitted coordinate the calibration moved into the preset (its
/// parameters at pb); returns the parameters moved.
std::vector<Param> move_preset(FlatCalibrator& cal, const cloth::FabricParams& pb)
{
    std::vector<Param> moved;
    for (int i = 0; i < static_cast<int>(cal.vars.size()); ++i)
        if (cal.best_x[i] != cal.x[i])
            for (Param q : cal.vars[static_cast<std::size_t>(i)].params) {
                cal.kept.params[q] = pb[q];
                if (std::find(moved.begin(), moved.end(), q) == moved.end()) moved.push_back(q);
            }
    return moved;
}

/// FlatCalibration::moved for the moved parameters; returns those besides the
/// bendings as the reason names them.
std::string record_moves(FlatCalibrator& cal, const std::vector<Param>& moved, const cloth::FabricParams& pb)
{
    const cloth::FabricParams p0 = cal.ev.params_at(cal.x);
    std::string others; // the moved parameters besides the bendings, for the reason
    for (Param q : moved) {
        const std::string key(cloth::spec(q).key);
        const double before = p0[q];
        cal.c.moved.push_back({key, before, pb[q]});
        if (q == Param::BendWarp || q == Param::BendWeft) continue;
        char o[160];
        if (before > 0 && cloth::spec(q).log_scale)
            std::snprintf(o, sizeof o, "%s%s x %.3f", others.empty() ? "" : ", ", key.c_str(), pb[q] / before);
        else
            std::snprintf(o, sizeof o, "%s%s %.3g -> %.3g", others.empty() ? "" : ", ", key.c_str(), before, pb[q]);
        others += o;
    }
    return others;
}

/// The moved parameters' estimates take the preset's values, each with a note of
/// the optimum's value and the calibration that moved it.
void note_moved_estimates(FlatCalibrator& cal, const std::vector<Param>& moved)
{
    const FitResult::FlatCalibration& c = cal.c;
    char buf[700];
    for (auto& e : cal.kept.estimates) {
        if (std::find(moved.begin(), moved.end(), e.id) == moved.end()) continue;
        const double fitted = e.value;
        e.value = cal.kept.params[e.id];
        const bool inside = e.value >= e.lower95 && e.value <= e.upper95;
        if (c.fold_search)
            std::snprintf(buf, sizeof buf,
                          "the contours' optimum %.3g moved along their profile to %.3g so the preset draped from flat lays the record's fold count "
                          "within 1 and comes closer to its D (%s its 95 %% interval; the notes before are the optimum's)",
                          fitted, e.value, inside ? "inside" : "outside");
        else
            std::snprintf(buf, sizeof buf,
                          "the contours' optimum %.3g scaled by %.3f so the preset draped from flat gives the record's D (%s its 95 %% interval; "
                          "the notes before are the optimum's)",
                          fitted, c.scale, inside ? "inside" : "outside");
        e.note = e.note.empty() ? buf : e.note + "; " + buf;
    }
}

} // namespace

bool FlatCalibrator::apply()
{
    char buf[700];
    if (best_records.empty()) {
        std::snprintf(buf, sizeof buf,
                      "draped from flat the preset misses the record's D by %+.1f points%s (sigma %.1f); no bending scale tried brought its drapes "
                      "closer with the fold count within 1: kept as fitted",
                      e0, over.c_str(), c.tolerance);
        c.reason = buf;
        return false;
    }
    c.applied = true;
    c.error_after = best_e;
    c.fold_error_after = best_folds;
    const cloth::FabricParams pb = ev.params_at(best_x);
    c.scale = pb[Param::BendWarp] / c.bend_warp_fitted;
    // Every fitted coordinate the calibration moved goes into the preset.
    const std::vector<Param> moved = move_preset(*this, pb);
    kept.records = std::move(best_records);
    c.chi2_increase = lin_cost(best_x - x);
    const std::string others = record_moves(*this, moved, pb);
    note_moved_estimates(*this, moved);
    const std::string cost = std::isfinite(c.chi2_increase) ? fmt_chi2(c.chi2_increase) : std::string("not computed (no Jacobian at the optimum)");
    if (c.fold_search) {
        std::snprintf(buf, sizeof buf,
                      "draped from flat the contours' optimum laid a fold count %.0f off the record's (D %+.1f points%s); a step along the contours' "
                      "profile, %.1f sigma (bendings x %.3f%s%s), lays it within %.0f (D %+.1f points, sigma %.1f); the fitted terms' chi2 %s",
                      folds0, e0, over.c_str(), c.fold_sigmas, c.scale, others.empty() ? "" : ", ", others.c_str(), best_folds, best_e, c.tolerance,
                      cost.c_str());
    } else {
        std::snprintf(buf, sizeof buf,
                      "draped from flat the contours' optimum missed the record's D by %+.1f points%s (sigma %.1f); both bendings scaled by %.3f "
                      "(ratio kept): %+.1f points from flat; the fitted terms' chi2 %s",
                      e0, over.c_str(), c.tolerance, c.scale, best_e, cost.c_str());
    }
    c.reason = buf;
    return true;
}

void FlatCalibrator::drape_preset_as_saved()
{
    // The preset as saved, draped as the fit drapes (warm from the optimum's rest
    // states, the fit's seeds and starts): the "as fitted" rows are the contours'
    // optimum's, and a user who drapes the saved preset as the fit did gets these.
    // Its chi2 is the drapes' own, not the linearised one above. Cancelled here:
    // the preset rows say nothing (NaN) and the reason says why.
    char buf[700];
    c.chi2_preset = std::numeric_limits<double>::quiet_NaN();
    Evaluation pe;
    ev.announce(Stage::PresetAsSaved);
    try {
        pe = ev.evaluate_params(kept.params, Start::Best);
    } catch (const CancelledFit&) {
        for (auto& rf : kept.records) {
            rf.preset_moved = true;
            rf.preset_converged = false;
            rf.preset_features = DrapeFeatures{};
            rf.preset_dc_error_percent = rf.preset_node_error = std::numeric_limits<double>::quiet_NaN();
        }
        c.reason += "; its drapes as the fit drapes them were cancelled";
        throw;
    }
    ev.report(Stage::PresetAsSaved);
    double dsum = 0, nsum = 0;
    int nd_p = 0, nn_p = 0;
    for (std::size_t r = 0; r < R && r < pe.features.size(); ++r) {
        RecordFit& rf = kept.records[r];
        set_preset(rf, pe.features[r], pe.sims[r], true);
        if (std::isfinite(rf.preset_dc_error_percent)) dsum += rf.preset_dc_error_percent, ++nd_p;
        if (std::isfinite(rf.preset_node_error)) nsum += rf.preset_node_error, ++nn_p;
    }
    c.chi2_preset = pe.chi2;
    const std::string over_p = nd_p > 1 ? " (mean over " + std::to_string(nd_p) + " records)" : std::string();
    std::snprintf(buf, sizeof buf,
                  "; draped as the fit drapes (warm from the optimum's rest states) the preset gives D %+.1f points, nodes %+.1f%s (the fitted "
                  "terms' chi2 %.1f%s against the optimum's %.1f)",
                  nd_p ? dsum / nd_p : std::numeric_limits<double>::quiet_NaN(), nn_p ? nsum / nn_p : std::numeric_limits<double>::quiet_NaN(),
                  over_p.c_str(), pe.chi2, pe.at_rest() ? "" : ", a drape not at rest", kept.chi2);
    c.reason += buf;
}

void calibrate_from_flat(Evaluator& ev, const std::vector<FitVariable>& vars, const Eigen::VectorXd& x, const Eigen::MatrixXd& J_opt,
                         FitResult& kept)
{
    FlatCalibrator cal(ev, vars, x, J_opt, kept);
    if (!cal.needs_calibration() || !cal.bendings_scalable()) return;
    cal.prepare_steps();
    FitResult::FlatCalibration& c = cal.c;
    char buf[700];
    try {
        if (cal.folds0 > 1) {
            // 1. The fold count: steps along the contours' profile of the bendings,
            // screened on the fit grid's drapes; then D by a bending scale on the same
            // drapes; the finer grid's drape once, for the preset that is kept.
            if (!cal.step_fold_count()) return;
        } else if (std::abs(cal.e0) > c.tolerance && cal.slope_ok) {
            // 2. D alone (the fold count within 1): both bendings scaled by one factor.
            cal.scale_for_d();
        } else {
            std::snprintf(buf, sizeof buf, "draped from flat the preset misses the record's D by %+.1f points%s, but D's sensitivity to the bending at the optimum is "
                          "not available or not positive: not calibrated", cal.e0, cal.over.c_str());
            c.reason = buf;
            return;
        }
    } catch (const CancelledFit&) {
        std::snprintf(buf, sizeof buf, "draped from flat the preset %s (D %+.1f points%s); the calibration was cancelled: kept as fitted", cal.miss.c_str(), cal.e0,
                      cal.over.c_str());
        c.reason = buf;
        throw;
    }
    if (!cal.apply()) return;
    cal.drape_preset_as_saved();
}

} // namespace drape::estimate::detail
