// The flat calibration's fold-count step (docs/decisions/0020-flat-calibration.md):
// when the optimum's drapes from flat lay a fold count more than 1 off the
// record's, a step of the bendings along the contours' profile (the other fitted
// coordinates follow to where the linearised contours are least), screened on the
// fit grid's drapes; then D by a bending scale on the same drapes and the finer
// grid's drape for the preset that is kept.
#include "engine/estimate/detail/flat_calibration.hpp"
#include "engine/estimate/detail/pipeline.hpp"
#include "engine/estimate/detail/stages.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace drape::estimate::detail {

using cloth::Param;

FlatCalibrator::FoldProfile FlatCalibrator::fold_profile() const
{
    FoldProfile fp;
    // The profile's direction per decade of the bendings: the other coordinates
    // where the linearised contours are least for that bending, from the rows
    // the fit linearises - a line through the optimum (the follower of the
    // step; the optimum is the search's, not exactly the linearised minimum).
    fp.sign = signed0 < 0 ? -1.0 : 1.0; // too few folds: softer bendings; too many: stiffer
    if (!have_J) fp.why_not = "without the contours' Jacobian at the optimum there is no profile to step along";
    else if (signed0 == 0) fp.why_not = "its drapes lay as many folds too many as too few";
    fp.dir = Eigen::VectorXd::Zero(x.size());
    std::vector<char> rows(kept.residuals.size());
    for (std::size_t k = 0; k < rows.size(); ++k) rows[k] = linearised_term(kept.residuals[k]) ? 1 : 0;
    // A coordinate at a bound the profile would push it past is held there (its
    // column out of J) and the profile found again for the others.
    Eigen::MatrixXd Jp = have_J ? J_opt : Eigen::MatrixXd();
    // A shear held at the typical value (ShearHold::Auto) stays held.
    const int shear_var = sole_variable(vars, Param::Shear);
    fp.shear_held = kept.shear_hold.held && have_J && shear_var >= 0;
    if (fp.shear_held) {
        fp.held.push_back(shear_var);
        Jp.col(shear_var).setZero();
    }
    for (int round = 0; fp.why_not.empty() && round <= static_cast<int>(vars.size()); ++round) {
        fp.dir = profile_direction(Jp, rows, bend, fp.unit);
        for (int i : fp.held) fp.dir[i] = 0;
        int pushed = -1;
        for (int i = 0; i < static_cast<int>(vars.size()) && pushed < 0; ++i) {
            if (is_bend(i) || std::find(fp.held.begin(), fp.held.end(), i) != fp.held.end()) continue;
            const FitVariable& v = vars[static_cast<std::size_t>(i)];
            const double tiny = 1e-9 * (v.upper - v.lower);
            if ((fp.sign * fp.dir[i] > 0 && x[i] >= v.upper - tiny) || (fp.sign * fp.dir[i] < 0 && x[i] <= v.lower + tiny)) pushed = i;
        }
        if (pushed < 0) break;
        fp.held.push_back(pushed);
        Jp.col(pushed).setZero();
    }
    if (fp.why_not.empty() && (!(fp.unit > 0) || !std::isfinite(fp.unit))) fp.why_not = "the contours do not see the bendings at the optimum";
    fp.sigma_t = fp.why_not.empty() ? std::sqrt(s2 / fp.unit) : 0.0; // the profile's sigma [decades of bending]
    return fp;
}

std::string FlatCalibrator::follower_rate(const FoldProfile& fp, int i, const char* verb) const
{
    const FitVariable& v = vars[static_cast<std::size_t>(i)];
    char r[160];
    std::snprintf(r, sizeof r, "%s %s %.3g %s", v.name.c_str(), verb, std::abs(fp.dir[i]), v.log_scale ? "decades" : "of its unit");
    return std::string(r);
}

double FlatCalibrator::profile_step(FoldProfile& fp, double k) const
{
    double t = fp.sign * k * fp.sigma_t;
    fp.limit_var = -1;
    for (int i = 0; i < static_cast<int>(vars.size()); ++i) {
        const FitVariable& v = vars[static_cast<std::size_t>(i)];
        const double move = t * fp.dir[i];
        if (move == 0) continue;
        const double cap = k * (v.log_scale ? 1.0 : 0.1 * (v.upper - v.lower));
        const double box = move > 0 ? v.upper - x[i] : x[i] - v.lower;
        const double room = std::min(cap, box);
        if (std::abs(move) > room) {
            t *= std::max(0.0, room) / std::abs(move);
            fp.limit_var = i;
            fp.limit_by_cap = cap < box;
        }
    }
    return t;
}

void FlatCalibrator::check_profile_steps(FoldProfile& fp) const
{
    // A profile no other coordinate follows is a bending scale alone, which
    // does not mend the fold count without losing D; one that leaves the box
    // at once has no step to draw.
    if (!fp.why_not.empty()) return;
    bool follows = false;
    for (int i = 0; i < static_cast<int>(vars.size()); ++i) {
        if (is_bend(i)) continue;
        const FitVariable& v = vars[static_cast<std::size_t>(i)];
        follows = follows || std::abs(fp.dir[i]) > 1e-3 * (v.log_scale ? 1.0 : v.upper - v.lower);
    }
    if (!follows) {
        fp.why_not = std::string("the contours' profile moves the bendings alone (") +
                     (fp.held.empty() ? "no other fitted coordinate follows them"
                      : fp.held.size() == 1 && fp.shear_held ? "the shear is held at the typical value"
                      : fp.shear_held ? "the shear is held at the typical value, the others that would follow are at their bounds"
                                      : "the others that would follow are at their bounds") +
                     "), and one bending scale does not mend the fold count without losing D";
        return;
    }
    if (std::abs(profile_step(fp, 1.0)) >= 0.01) return;
    const FitVariable& v = vars[static_cast<std::size_t>(std::max(fp.limit_var, 0))];
    char w[300];
    if (fp.limit_var >= 0 && fp.limit_by_cap)
        std::snprintf(w, sizeof w,
                      "the contours' profile is too steep to step along (%s per decade of the bendings: the "
                      "contours hardly see the bendings along it)",
                      follower_rate(fp, fp.limit_var, "would move").c_str());
    else
        std::snprintf(w, sizeof w, "the contours' profile leaves the fit's box at once (%s at its bound)", fp.limit_var >= 0 ? v.name.c_str() : "a coordinate");
    fp.why_not = w;
}

bool FlatCalibrator::step_fold_count()
{
    char buf[700];
    c.fold_search = true;
    FoldProfile fp = fold_profile();
    // The step of k sigma of the profile (its curvature: the linearised chi2
    // rises by k^2 s2 along it from a minimum), shortened where a coordinate
    // would leave the box or move more than k decades (k tenths of a linear
    // range): the point stays on the profile's line (profile_step).
    check_profile_steps(fp);
    c.fold_direction = fp.why_not.empty() ? fp.sign : 0;
    Eigen::VectorXd cand;
    double cand_e = 0, cand_score = best_score, cand_sigmas = 0;
    double t_prev = 0;
    double reached = 0;   // the farthest step drawn [sigmas of the profile]
    int reach_limit = -1; // ... and the coordinate whose cap shortened it (-1: none)
    for (double k : {1.0, 2.0}) {
        if (!fp.why_not.empty()) break;
        const double t = profile_step(fp, k);
        // A step the box shortened to (next to) the last one draws nothing new.
        if (std::abs(t - t_prev) < 0.01 || std::abs(t) < 0.01) break;
        t_prev = t;
        Eigen::VectorXd xs = x + t * fp.dir;
        for (int i = 0; i < static_cast<int>(vars.size()); ++i) {
            const FitVariable& v = vars[static_cast<std::size_t>(i)];
            xs[i] = std::clamp(xs[i], v.lower, v.upper); // rounding only: profile_step kept it inside
        }
        const double sigmas = std::abs(t) / fp.sigma_t; // k, or less where the box shortened it
        reached = sigmas;
        reach_limit = fp.limit_var >= 0 && fp.limit_by_cap ? fp.limit_var : -1;
        ev.draw_from_flat(xs, Stage::FromFlatFoldCount, Evaluator::FlatDraw::FitGrid);
        ++c.steps;
        double e = 0, folds = 0;
        if (measure(e, folds, nullptr) != n_used) break;
        c.history.push_back({bend_scale(xs), e, folds, "fold count", sigmas, lin_cost(xs - x), false});
        if (folds <= 1 && score(e, folds) < cand_score) {
            // The step whose drapes are the candidate.
            cand = xs;
            cand_e = e;
            cand_score = score(e, folds);
            cand_sigmas = sigmas;
            break;
        }
    }
    if (cand.size() > 0) return confirm_fold_step(cand, cand_e, cand_score, cand_sigmas);
    std::string why_not = fp.why_not;
    if (why_not.empty()) {
        // How far the steps reached: a coordinate the contours hardly see moves
        // many decades per decade of the bendings, and its cap (k decades at k
        // sigma) shortens the step to a fraction of a sigma (DL-A05: shear 29.7
        // decades per decade, 2 sigma -> 0.46).
        char w[400];
        if (reach_limit >= 0)
            std::snprintf(w, sizeof w,
                          "no step of the bendings along the contours' profile laid it within 1 with its drapes closer to the record "
                          "(the steps reached %.2f sigma: %s per decade of the bendings along the profile, and its "
                          "move is capped at %s per sigma)",
                          reached, follower_rate(fp, reach_limit, "moves").c_str(),
                          vars[static_cast<std::size_t>(reach_limit)].log_scale ? "a decade" : "a tenth of its range");
        else
            std::snprintf(w, sizeof w,
                          "no step of the bendings along the contours' profile within %.2g sigma laid it within 1 with its drapes closer "
                          "to the record",
                          reached > 0 ? reached : 2.0);
        why_not = w;
    }
    std::snprintf(buf, sizeof buf, "draped from flat the preset lays a fold count %.0f off the record's (D %+.1f points%s); %s: not calibrated",
                  folds0, e0, over.c_str(), why_not.c_str());
    c.reason = buf;
    c.fold_search_failed = true;
    return false;
}

bool FlatCalibrator::confirm_fold_step(Eigen::VectorXd cand, double cand_e, double cand_score, double cand_sigmas)
{
    char buf[700];
    // The step whose drapes are the candidate.
    auto take = [&](const Eigen::VectorXd& xs, double e, double folds) {
        cand = xs;
        cand_e = e;
        cand_score = score(e, folds);
    };
    // D on the fit grid's drapes, from the step's point: one step (each costs a
    // set of drapes; the fit's time is bounded).
    if (std::abs(cand_e) > c.tolerance && slope_ok) {
        Eigen::VectorXd xs;
        if (scaled(cand, std::clamp(-cand_e / slope, -max_step, max_step), xs)) {
            ev.draw_from_flat(xs, Stage::FromFlatCalibrated, Evaluator::FlatDraw::FitGrid);
            ++c.steps;
            double e = 0, folds = 0;
            if (measure(e, folds, nullptr) == n_used) {
                c.history.push_back({bend_scale(xs), e, folds, "D", 0, lin_cost(xs - x), false});
                if (folds <= 1 && score(e, folds) < cand_score) take(xs, e, folds);
            }
        }
    }
    // The finer grid's drape for the preset that is kept (the fit grid's drapes
    // of the candidate are the evaluator's kept ones, its coarse level theirs).
    ev.draw_from_flat(cand, Stage::FromFlatCalibrated);
    double e = 0, folds = 0;
    bool fine_rested = true;
    for (std::size_t r = 0; r < R && finer; ++r)
        if (const Evaluator::FineDrape* f = ev.cold_fine(r); used[r] && (!f || !f->at_rest)) fine_rested = false;
    if (measure(e, folds, nullptr) != n_used || !fine_rested) {
        std::snprintf(buf, sizeof buf,
                      "draped from flat the preset lays a fold count %.0f off the record's (D %+.1f points%s); a step along the contours' "
                      "profile laid it within 1 on the fit grid, but its drape on the finer grid did not come to rest: not calibrated",
                      folds0, e0, over.c_str());
        c.reason = buf;
        c.fold_search_failed = true;
        return false;
    }
    const double cost = lin_cost(cand - x);
    c.history.push_back({bend_scale(cand), e, folds, "preset", 0, cost, finer});
    // Kept when its drapes are within 1 fold and closer to the record by more
    // than the contours lose: the drapes' score (D error in the D channel's
    // sigma, the worst drape's fold error in the node channel's, squared and
    // summed) against the contours' linearised chi2 increase scaled as the
    // intervals are - both the record's data, weighed on one chi2 scale.
    if (folds <= 1 && score(e, folds) < best_score && !(cost / s2 < best_score - score(e, folds))) {
        std::snprintf(buf, sizeof buf,
                      "draped from flat the preset lays a fold count %.0f off the record's (D %+.1f points%s); a step along the contours' "
                      "profile lays it within 1 (D %+.1f points) but costs the contours more (linearised chi2 %+.1f, scaled %+.1f) than "
                      "it gains from flat (%.1f): not calibrated",
                      folds0, e0, over.c_str(), e, cost, cost / s2, best_score - score(e, folds));
        c.reason = buf;
        c.fold_search_failed = true;
        return false;
    }
    if (!(folds <= 1 && score(e, folds) < best_score)) {
        std::snprintf(buf, sizeof buf,
                      "draped from flat the preset lays a fold count %.0f off the record's (D %+.1f points%s); a step along the contours' "
                      "profile laid it within 1 on the fit grid, but with the finer grid's drape it is %.0f off (D %+.1f points): not calibrated",
                      folds0, e0, over.c_str(), folds, e);
        c.reason = buf;
        c.fold_search_failed = true;
        return false;
    }
    c.fold_sigmas = cand_sigmas;
    keep(cand, e, folds);
    return true;
}

} // namespace drape::estimate::detail
