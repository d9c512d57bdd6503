// The fit's linearisation at a point (Evaluator::jacobian, Evaluator::effect_signatures):
// the rest states' exact sensitivities carried through the features by central
// differences, per record and seed, averaged over the seeds into the residual rows.
#include "engine/estimate/detail/evaluator.hpp"

#include "engine/cloth/rest_sensitivity.hpp"
#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

namespace drape::estimate::detail {

using cloth::Param;

namespace {

/// Whether the slice of term t's depth closed for the same fraction of seeds on
/// both sides of a difference (terms without a depth: always).
bool same_closure(const std::vector<double>& a, const std::vector<double>& b, const DrapeFeatures& meas, const ResidualTerm& t)
{
    if (t.depth_m == 0 || t.kind == "dc" || t.kind == "hem" || t.kind == "nodes") return true;
    for (std::size_t d = 0; d < meas.contours.size(); ++d)
        if (std::abs(meas.contours[d].depth_m - t.depth_m) < 1e-9) return d >= a.size() || d >= b.size() || a[d] == b[d];
    return true;
}

/// Whether a record's measurement model takes the instrument effect out of its contours.
bool removed_by_measurement_model(const EffectSpec& sp, const MeasuredDrape& rec)
{
    if (sp.kind == EffectKind::ProfilerAxis) return rec.recentre_contours || rec.untilt_contours;
    if (sp.kind == EffectKind::ProfilerTilt) return rec.untilt_contours;
    return false;
}

/// The closure rows count seeds whose slice closed: no derivative (a flip between
/// x + d and x - d would read as a slope of thousands).
bool linearised_row(const ResidualTerm& t) { return t.smooth && t.fitted && t.sigma > 0 && t.kind != "closure"; }

// Steps of the effects' differences.
constexpr double kRel = 1e-3;   ///< relative change of a parameter along its dx/d ln p (first order: any small step)
constexpr double kScale = 1e-3; ///< scale error
constexpr double kShift = 1e-4; ///< [m] axis shift
constexpr double kTilt = 1e-3;  ///< [rad] axis tilt
constexpr double kDepth = 1e-4; ///< [m] the cuts' depth datum
constexpr double kLin = 1e-3;   ///< fraction of a specimen effect's switched-on size along its response

/// The size of an effect's difference, in its amplitude's unit.
double effect_unit(const EffectSpec& sp)
{
    switch (sp.kind) {
    case EffectKind::Parameter: return kRel;
    case EffectKind::Switch: return 1.0;
    case EffectKind::Specimen: return kLin * sp.density_gradient;
    case EffectKind::ProfilerAxis: return kShift;
    case EffectKind::ProfilerTilt: return kTilt;
    case EffectKind::ProfilerDepth: return kDepth;
    case EffectKind::CameraScale:
    case EffectKind::ProfilerScale: return kScale;
    }
    return kScale;
}

/// Whether effect sp reaches row t: the instruments act on their own channels only.
bool effect_reaches(const EffectSpec& sp, const ResidualTerm& t)
{
    const bool photo_row = t.kind == "dc" || t.kind == "hem";
    if (sp.kind == EffectKind::CameraScale && !photo_row) return false;
    const bool profiler = sp.kind == EffectKind::ProfilerScale || sp.kind == EffectKind::ProfilerAxis || sp.kind == EffectKind::ProfilerTilt ||
                          sp.kind == EffectKind::ProfilerDepth;
    return !(profiler && photo_row);
}

/// One record's drape of one seed at the fit's point, measured as the fit measures.
struct SeedDrape {
    const MeasuredDrape& rec;
    const cloth::Positions& x; ///< its rest state
    cloth::DrapeSetup setup;
    cloth::FabricParams params; ///< the record's (params_for_record)
    cloth::Material material;
    std::unique_ptr<cloth::ClothSystem> sys;
    SeedDrape(const MeasuredDrape& r, const cloth::Positions& rest, const cloth::DrapeSetup& su, const cloth::FabricParams& p,
              const cloth::ModelOptions& mo)
        : rec(r), x(rest), setup(su), params(p), material(p), sys(cloth::make_drape_system(material, su, mo))
    {
    }
    DrapeFeatures measure(const cloth::Positions& X)
    {
        sys->x = X;
        return drape_features(cloth::measure_drape(*sys, setup), rec);
    }
};

/// SeedDrape with its rest state's responses to the parameters and the specimen's
/// effects (one factorisation), for the effects' signatures.
struct SeedResponses : SeedDrape {
    using SeedDrape::SeedDrape;
    std::vector<Param> qs; ///< the parameters of resp.params, in order
    cloth::RestResponses resp;
    bool sens_ok = true;
};

/// The features of one seed's drape with effect sp on (one per column of its
/// signature): along the rest state's response for the parameters and the
/// specimen's effects, re-solved for a switch, moved as the instrument would for
/// the instruments'. `resolves` counts the re-solves; `failed`: a switch's drape
/// did not come to rest.
std::vector<DrapeFeatures> effect_on(const EffectSpec& sp, SeedResponses& d, std::size_t specimen_first, const FitOptions& opt,
                                     long& resolves, bool& failed)
{
    const cloth::Positions& x = d.x;
    switch (sp.kind) {
    case EffectKind::Parameter: {
        if (!d.sens_ok) return {};
        cloth::Positions dx = cloth::Positions::Zero(x.rows(), 3);
        for (std::size_t m = 0; m < sp.params.size(); ++m)
            for (std::size_t i = 0; i < d.qs.size(); ++i)
                if (d.qs[i] == sp.params[m]) dx += effect_weight(sp, m) * d.params[d.qs[i]] * d.resp.params[i].dx; // d x / d ln p
        return {d.measure(x + kRel * dx)};
    }
    case EffectKind::Switch: {
        cloth::FabricParams q = d.params;
        for (Param w : sp.params) q[w] = sp.on_value;
        cloth::DrapeSetup su = d.setup;
        su.disc_grip = su.disc_grip || sp.disc_grip;
        cloth::ModelOptions mo = opt.model_options;
        if (sp.vertex_contact) mo.edge_contact = false;
        if (sp.self_contact) mo.self_collision = true;
        cloth::RestOptions ro = opt.rest;
        ro.cancel = opt.cancel;
        ro.progress = nullptr;
        const cloth::DrapeResult r = cloth::simulate_drape_from(cloth::Material(q), su, x, ro, mo);
        ++resolves;
        if (!r.status.converged()) failed = true; // not at rest: no signature
        return {drape_features(r, d.rec)};
    }
    case EffectKind::Specimen: { // the set-up's response along x, then y, a kLin of the way
        if (!d.sens_ok) return {};
        std::vector<DrapeFeatures> f;
        for (std::size_t c = 0; c < 2; ++c) f.push_back(d.measure(x + kLin * d.resp.setups[specimen_first + c]));
        return f;
    }
    case EffectKind::CameraScale: // the photos: every length, the hem's height too
        return {d.measure(x * (1 + kScale))};
    case EffectKind::ProfilerScale: { // the laser: radii only (the depths are the profiler's own setting)
        cloth::Positions X = x;
        X.leftCols(2) *= 1 + kScale;
        return {d.measure(X)};
    }
    case EffectKind::ProfilerAxis: {
        cloth::Positions X = x, Y = x;
        X.col(0).array() += kShift;
        Y.col(1).array() += kShift;
        return {d.measure(X), d.measure(Y)};
    }
    case EffectKind::ProfilerDepth: { // a cut declared at depth d taken at d + delta: the plane z = -d meets the drape moved up by delta
        cloth::Positions X = x;
        X.col(2).array() += kDepth;
        return {d.measure(X)};
    }
    case EffectKind::ProfilerTilt: { // a cut at depth d (z = -d) lands d tan(t) sideways
        cloth::Positions X = x, Y = x;
        X.col(0) -= kTilt * x.col(2);
        Y.col(1) -= kTilt * x.col(2);
        return {d.measure(X), d.measure(Y)};
    }
    }
    return {};
}

} // namespace

bool slopes_agree(double full, double half, double floor)
{
    return std::abs(full - half) <= 0.1 * std::max(std::abs(full), std::abs(half)) + floor;
}

std::vector<ResidualTerm> Evaluator::seed_terms(int r, const FeatureTable& feats, std::size_t column, std::vector<double>& closed) const
{
    std::vector<DrapeFeatures> at;
    for (const auto& seed : feats[static_cast<std::size_t>(r)]) at.push_back(seed[column]);
    return residual_terms(r, m_meas[static_cast<std::size_t>(r)], average_features(at, &closed), closed, m_noise);
}

// ---- the Jacobian ---------------------------------------------------------

bool Evaluator::at_switch(const Eigen::VectorXd& x, int i) const
{
    const auto& v = m_vars[static_cast<std::size_t>(i)];
    return !v.log_scale && v.lower == 0 && x[i] <= 1e-6 * (v.upper - v.lower);
}

double Evaluator::column_step(int i) const
{
    const auto& v = m_vars[static_cast<std::size_t>(i)];
    return v.log_scale ? 1e-3 : 1e-3 * (v.upper - v.lower);
}

std::vector<char> Evaluator::exact_columns(const Eigen::VectorXd& x, const cloth::FabricParams& p, const Evaluation& e) const
{
    const int n = static_cast<int>(m_vars.size());
    std::vector<char> exact(static_cast<std::size_t>(n), e.at_rest() ? 1 : 0);
    for (int i = 0; i < n; ++i)
        for (Param q : m_vars[static_cast<std::size_t>(i)].params)
            if (!(p[q] > cloth::spec(q).lower) || !(p[q] < cloth::spec(q).upper) || !cloth::spec(q).affects_statics) exact[static_cast<std::size_t>(i)] = 0;
    for (int i = 0; i < n; ++i)
        if (at_switch(x, i)) exact[static_cast<std::size_t>(i)] = 0;
    return exact;
}

bool Evaluator::sensitivity_features(const cloth::FabricParams& p, const Evaluation& e, const std::vector<char>& exact, FeatureTable& feats)
{
    const int S = std::max(1, m_opt.seeds_per_evaluation);
    const int R = static_cast<int>(m_recs.size());
    const int n = static_cast<int>(m_vars.size());
    feats.assign(static_cast<std::size_t>(R),
                 std::vector<std::vector<DrapeFeatures>>(static_cast<std::size_t>(S), std::vector<DrapeFeatures>(static_cast<std::size_t>(4 * n))));
    std::vector<Param> qs;
    for (int i = 0; i < n; ++i)
        if (exact[static_cast<std::size_t>(i)])
            for (Param q : m_vars[static_cast<std::size_t>(i)].params) qs.push_back(q);
    if (qs.empty()) return false;
    const int nthreads = std::clamp(m_opt.parallel_seeds, 1, R * S);
    try {
        parallel_for(static_cast<std::size_t>(R * S), nthreads, [&](std::size_t j) {
            const int r = static_cast<int>(j) / S, s = static_cast<int>(j) % S;
            const auto& rec = m_recs[static_cast<std::size_t>(r)];
            const auto& sim = e.sims[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
            SeedDrape d(rec, sim.x, setup_for(r, m_opt.seed + static_cast<std::uint64_t>(s), true), params_for_record(p, rec), m_opt.model_options);
            const auto sens = cloth::rest_sensitivities(d.material, d.setup, sim.x, qs, m_opt.model_options);
            std::size_t k = 0;
            for (int i = 0; i < n; ++i) {
                if (!exact[static_cast<std::size_t>(i)]) continue;
                const auto& v = m_vars[static_cast<std::size_t>(i)];
                cloth::Positions dxdc = cloth::Positions::Zero(sim.x.rows(), 3);
                for (Param q : v.params) {
                    // d value / d coordinate: value ln 10 on a log scale.
                    const double dv = v.log_scale ? d.params[q] * std::log(10.0) : 1.0;
                    dxdc += dv * sens[k++].dx;
                }
                const double step = column_step(i);
                auto& f = feats[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
                const double steps[4] = {step, -step, 0.5 * step, -0.5 * step};
                for (int m = 0; m < 4; ++m) f[static_cast<std::size_t>(4 * i + m)] = d.measure(sim.x + steps[m] * dxdc);
            }
        });
    } catch (const drape::Error&) {
        return false; // not a stable rest state: differences of re-solves
    }
    m_work.factorisations += R * S;
    m_work.back_substitutions += static_cast<long>(R * S) * static_cast<long>(qs.size());
    return true;
}

void Evaluator::exact_column(int i, const Evaluation& e, const FeatureTable& feats, Eigen::MatrixXd& J)
{
    const double d = column_step(i);
    const std::vector<std::size_t>& first = m_first_term;
    for (int r = 0; r < static_cast<int>(m_recs.size()); ++r) {
        // The seed-averaged terms at the four points of the column.
        std::vector<ResidualTerm> t[4];
        std::vector<double> closed[4];
        const auto& mr = m_meas[static_cast<std::size_t>(r)];
        for (int k = 0; k < 4; ++k) t[k] = seed_terms(r, feats, static_cast<std::size_t>(4 * i + k), closed[k]);
        const std::size_t count = first[static_cast<std::size_t>(r) + 1] - first[static_cast<std::size_t>(r)];
        if (t[0].size() != count || t[1].size() != count || t[2].size() != count || t[3].size() != count)
            continue; // rows would not line up: leave the column's rows at 0
        for (std::size_t k = 0; k < count; ++k) {
            const std::size_t row = first[static_cast<std::size_t>(r)] + k;
            // A depth whose slice closed for another set of seeds on the two
            // sides averages other drapes: no derivative there.
            if (!same_closure(closed[0], closed[1], mr, e.terms[row]) || !same_closure(closed[2], closed[3], mr, e.terms[row])) continue;
            if (!linearised_row(e.terms[row])) continue;
            bool finite = true;
            for (int q = 0; q < 4; ++q) finite = finite && std::isfinite(t[q][k].simulated);
            if (!finite) continue;
            const double full = (t[0][k].simulated - t[1][k].simulated) / (2 * d) / e.terms[row].sigma;
            const double half = (t[2][k].simulated - t[3][k].simulated) / d / e.terms[row].sigma;
            // A feature that jumps between the points (a selection that switches: a
            // ray's outermost crossing, a vertex entering a window) has no
            // derivative for this column: 0, as for a closure flip, and counted. A
            // kink between them (a minimum's argmin switching within 1e-3 decades)
            // is dropped too: rare, and a zero only widens the interval.
            // The floor: 0.05 sigma per thousand steps (a decade of a log
            // coordinate, the range of a linear one).
            if (!slopes_agree(full, half, 0.05 * 1e-3 / d)) {
                ++m_work.jacobian_jumps;
                continue;
            }
            J(static_cast<Eigen::Index>(row), i) = full;
        }
    }
}

void Evaluator::resolved_column(int i, const Eigen::VectorXd& x, const Evaluation& e, Eigen::MatrixXd& J)
{
    // A one-sided difference of warm re-solves, into the box. From a rest state, a
    // re-solve that did not come to rest is no drape of the model: its difference
    // would be a slope of the solver's path. Then the other side; failing both,
    // the column stays 0 (the parameter reads as not seen by the data, and its
    // interval says so). Before any drape at rest (e not at rest) the differences
    // are all the search has, and are kept as they are.
    const auto& v = m_vars[static_cast<std::size_t>(i)];
    double h = v.log_scale ? 0.05 : 0.02 * (v.upper - v.lower);
    if (at_switch(x, i)) h = 0.2 * (v.upper - v.lower); // see at_switch
    Eigen::VectorXd xp = x;
    if (x[i] + h > v.upper) h = -h;
    xp[i] = x[i] + h;
    Evaluation ep = evaluate(xp, Start::Best);
    report(Stage::Jacobian);
    if (e.at_rest() && !ep.at_rest() && x[i] - h >= v.lower && x[i] - h <= v.upper) {
        h = -h;
        xp[i] = x[i] + h;
        ep = evaluate(xp, Start::Best);
        report(Stage::Jacobian);
    }
    if (e.at_rest() && !ep.at_rest()) return;
    for (std::size_t k = 0; k < m_first_term.back() && k < e.terms.size() && k < ep.terms.size(); ++k)
        if (linearised_row(e.terms[k]) && std::isfinite(ep.terms[k].simulated) && std::isfinite(e.terms[k].simulated))
            J(static_cast<Eigen::Index>(k), i) = (ep.terms[k].simulated - e.terms[k].simulated) / h / e.terms[k].sigma;
}

Eigen::MatrixXd Evaluator::jacobian(const Eigen::VectorXd& x, const Evaluation& e, bool resolves)
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    ++m_work.jacobians;
    const cloth::FabricParams p = params_at(x);
    const int n = static_cast<int>(m_vars.size());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(e.terms.size()), n);
    if (e.sims.size() != m_recs.size()) return J;
    // Which variables the sensitivities serve: every parameter of the group
    // nonzero and inside its bounds (clamped coordinates do not move anything),
    // and every drape at rest. A linear coordinate at a lower bound of 0 switches
    // an effect on (a radius, a buckling length) that enters as its square or
    // higher: its slope there is 0 (a start at 0 is stored as 1e-300), and a small
    // difference sees nothing, so the search could never leave 0. The secant over
    // a fifth of the range (6 mm of a 30 mm radius) says whether switching it on
    // helps (at_switch, resolved_column).
    const std::vector<char> exact = exact_columns(x, p, e);
    // features[r][s][4 i + (0 up, 1 down, 2 half up, 3 half down)]: the difference
    // is taken at the step and at half of it, and a row whose two slopes disagree
    // has no derivative for that column. The step (column_step) only has to be
    // small against the metrics' own kinks (a shadow vertex crossing the rim): the
    // first-order path is linear.
    FeatureTable feats;
    const bool sens_ok = sensitivity_features(p, e, exact, feats);
    // The prior rows: linear in the log10 coordinates.
    for (std::size_t row = m_first_term.back(); row < e.terms.size(); ++row)
        for (int i = 0; i < n; ++i)
            J(static_cast<Eigen::Index>(row), i) = prior_slope(e.terms[row].kind, static_cast<std::size_t>(i)) / e.terms[row].sigma;
    if (m_first_term.back() + prior_terms(p).size() != e.terms.size()) return J; // not this evaluator's terms
    for (int i = 0; i < n; ++i) {
        if (sens_ok && exact[static_cast<std::size_t>(i)]) exact_column(i, e, feats, J);
        else if (resolves) resolved_column(i, x, e, J);
    }
    return J;
}

// ---- the candidate effects' signatures -------------------------------------

std::vector<Param> Evaluator::signatures_available(const cloth::FabricParams& p, bool all_at_rest, Eigen::Index rows,
                                                   std::vector<EffectSignature>& out) const
{
    const auto& lib = effect_library();
    out.assign(lib.size(), EffectSignature{});
    std::vector<Param> sens_params; // parameters whose dx/dp the sensitivities give
    for (std::size_t k = 0; k < lib.size(); ++k) {
        const EffectSpec& sp = lib[k];
        auto& sig = out[k];
        sig.spec = &sp;
        const int cols = sp.kind == EffectKind::ProfilerAxis || sp.kind == EffectKind::ProfilerTilt || sp.kind == EffectKind::Specimen ? 2 : 1;
        sig.columns = Eigen::MatrixXd::Zero(rows, cols);
        if (!all_at_rest) {
            sig.available = false;
            sig.why_not = "the fit's drapes are not at rest: no linearisation";
            continue;
        }
        // The measurement model removes the profiler's axis (re-centred stacks)
        // and its tilt (untilted stacks) from record and simulation alike: what
        // would be left of the signature is the resampling's rounding.
        bool removed_everywhere = sp.kind == EffectKind::ProfilerAxis || sp.kind == EffectKind::ProfilerTilt;
        for (const auto& rec : m_recs) removed_everywhere = removed_everywhere && removed_by_measurement_model(sp, rec);
        if (removed_everywhere) {
            sig.available = false;
            sig.why_not = "the measurement model removes it (--recentre-contours / --untilt-contours)";
            continue;
        }
        if (const std::string keys = fitted_by(sp, m_vars); !keys.empty()) {
            sig.available = false;
            sig.why_not = "the model fits it already (" + keys + ")";
        }
        if (!sig.available) continue;
        if (sp.kind == EffectKind::Parameter) {
            for (Param q : sp.params)
                if (!(p[q] > 0) || !cloth::spec(q).affects_statics) {
                    sig.available = false;
                    sig.why_not = std::string(cloth::spec(q).key) + " is 0 in this model (no relative change)";
                }
            if (sig.available)
                for (Param q : sp.params)
                    if (std::find(sens_params.begin(), sens_params.end(), q) == sens_params.end()) sens_params.push_back(q);
        } else if (sp.kind == EffectKind::Switch) {
            for (Param q : sp.params)
                if (p[q] != 0) {
                    sig.available = false;
                    sig.why_not = std::string(cloth::spec(q).key) + " is already on in this model";
                }
        }
    }
    return sens_params;
}

void Evaluator::signature_features(const cloth::FabricParams& p, const Evaluation& e, const std::vector<Param>& sens_params,
                                   std::vector<EffectSignature>& out, FeatureTable& off, std::vector<FeatureTable>& on)
{
    const auto& lib = effect_library();
    const int S = std::max(1, m_opt.seeds_per_evaluation);
    const int R = static_cast<int>(m_recs.size());
    // Features of every (record, seed) with each effect on: on[effect][r][s][column].
    on.assign(lib.size(), FeatureTable(static_cast<std::size_t>(R), std::vector<std::vector<DrapeFeatures>>(static_cast<std::size_t>(S))));
    off.assign(static_cast<std::size_t>(R), std::vector<std::vector<DrapeFeatures>>(static_cast<std::size_t>(S), std::vector<DrapeFeatures>(1)));
    long resolves = 0;
    std::atomic<bool> parameter_failed{false};
    std::vector<std::atomic<char>> switch_failed(lib.size());
    for (auto& f : switch_failed) f = 0;
    const auto t0 = Clock::now();
    const int nthreads = std::clamp(m_opt.parallel_seeds, 1, R * S);
    std::mutex count_mutex;
    parallel_for(static_cast<std::size_t>(R * S), nthreads, [&](std::size_t j) {
        const int r = static_cast<int>(j) / S, s = static_cast<int>(j) % S;
        const auto& rec = m_recs[static_cast<std::size_t>(r)];
        const auto& sim = e.sims[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
        SeedResponses d(rec, sim.x, setup_for(r, m_opt.seed + static_cast<std::uint64_t>(s), true), params_for_record(p, rec), m_opt.model_options);
        off[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)][0] = d.measure(sim.x);
        for (Param q : sens_params)
            if (d.params[q] > 0) d.qs.push_back(q);
        // The specimen's effects: the set-up changed along x, then y (responses on
        // the same factorisation as the parameters').
        std::vector<cloth::DrapeSetup> changed;
        std::vector<std::size_t> changed_first(lib.size(), 0);
        for (std::size_t k = 0; k < lib.size(); ++k)
            if (out[k].available && lib[k].kind == EffectKind::Specimen) {
                changed_first[k] = changed.size();
                for (int c = 0; c < 2; ++c) {
                    cloth::DrapeSetup su = d.setup;
                    su.density_gradient[c] = lib[k].density_gradient;
                    changed.push_back(su);
                }
            }
        try {
            if (!d.qs.empty() || !changed.empty()) d.resp = cloth::rest_responses(d.material, d.setup, sim.x, d.qs, changed, m_opt.model_options);
        } catch (const drape::Error&) {
            d.sens_ok = false; // not a stable rest state: no parameter signatures (the others need no Hessian)
            parameter_failed = true;
        }
        long my_resolves = 0;
        for (std::size_t k = 0; k < lib.size(); ++k) {
            if (!out[k].available) continue;
            bool failed = false;
            on[k][static_cast<std::size_t>(r)][static_cast<std::size_t>(s)] = effect_on(lib[k], d, changed_first[k], m_opt, my_resolves, failed);
            if (failed) switch_failed[k] = 1;
        }
        std::lock_guard lock(count_mutex);
        resolves += my_resolves;
    });
    m_work.simulations += resolves;
    m_work.simulation_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
    long specimen_columns = 0;
    for (std::size_t k = 0; k < lib.size(); ++k)
        if (out[k].available && lib[k].kind == EffectKind::Specimen) specimen_columns += 2;
    if ((!sens_params.empty() || specimen_columns > 0) && !parameter_failed) {
        m_work.factorisations += R * S;
        m_work.back_substitutions += static_cast<long>(R * S) * (static_cast<long>(sens_params.size()) + specimen_columns);
    }
    for (std::size_t k = 0; k < lib.size(); ++k) {
        if (!out[k].available) continue;
        if ((lib[k].kind == EffectKind::Parameter || lib[k].kind == EffectKind::Specimen) && parameter_failed) {
            out[k].available = false;
            out[k].why_not = "the Hessian at a rest state is not positive definite: no sensitivity";
        }
        if (switch_failed[k]) {
            out[k].available = false;
            out[k].why_not = "the drape with the effect switched on did not come to rest";
        }
    }
}

void Evaluator::signature_columns(EffectSignature& sig, const Evaluation& e, const FeatureTable& off, const FeatureTable& on) const
{
    const EffectSpec& sp = *sig.spec;
    const double unit = effect_unit(sp);
    const std::vector<std::size_t>& first = m_first_term;
    for (Eigen::Index c = 0; c < sig.columns.cols(); ++c)
        for (int r = 0; r < static_cast<int>(m_recs.size()); ++r) {
            std::vector<double> cu, cb;
            const auto tu = seed_terms(r, on, static_cast<std::size_t>(c), cu), tb = seed_terms(r, off, 0, cb);
            const auto& mr = m_meas[static_cast<std::size_t>(r)];
            const std::size_t count = first[static_cast<std::size_t>(r) + 1] - first[static_cast<std::size_t>(r)];
            if (tu.size() != count || tb.size() != count) continue;
            for (std::size_t i = 0; i < tu.size() && i < tb.size(); ++i) {
                const std::size_t row = first[static_cast<std::size_t>(r)] + i;
                const auto& t = e.terms[row];
                if (!linearised_row(t) || !same_closure(cu, cb, mr, t) || !effect_reaches(sp, t)) continue;
                if (removed_by_measurement_model(sp, m_recs[static_cast<std::size_t>(r)])) continue;
                if (!std::isfinite(tu[i].simulated) || !std::isfinite(tb[i].simulated)) continue;
                sig.columns(static_cast<Eigen::Index>(row), c) = (tu[i].simulated - tb[i].simulated) / unit / t.sigma;
            }
        }
}

std::vector<EffectSignature> Evaluator::effect_signatures(const Eigen::VectorXd& x, const Evaluation& e)
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    const cloth::FabricParams p = params_at(x);
    const bool all_at_rest = e.sims.size() == m_recs.size() && e.at_rest();
    std::vector<EffectSignature> out;
    const std::vector<Param> sens_params = signatures_available(p, all_at_rest, static_cast<Eigen::Index>(e.terms.size()), out);
    FeatureTable off;
    std::vector<FeatureTable> on;
    if (all_at_rest) signature_features(p, e, sens_params, out, off, on);
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    if (!all_at_rest || m_first_term.back() + prior_terms(p).size() != e.terms.size()) return out;
    for (std::size_t k = 0; k < out.size(); ++k)
        if (out[k].available) signature_columns(out[k], e, off, on[k]);
    return out;
}

} // namespace drape::estimate::detail
