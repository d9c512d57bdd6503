#include "engine/estimate/detail/evaluator.hpp"

#include "engine/cloth/rest_sensitivity.hpp"
#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>

namespace drape::estimate::detail {

using cloth::Param;

Evaluator::Evaluator(const std::vector<MeasuredDrape>& recs, const FitOptions& opt, std::vector<FitVariable> vars,
                     cloth::FabricParams base)
    : m_recs(recs), m_opt(opt), m_vars(std::move(vars)), m_base(base), m_t0(Clock::now())
{
    // Both sides of a residual are one draw of the fold pattern: the record
    // (one drape) and the mean of S simulated seeds. The variance of the
    // difference is floor^2 (1 + 1/S).
    m_noise = opt.noise;
    const double f = std::sqrt(1.0 + 1.0 / std::max(1, opt.seeds_per_evaluation));
    m_noise.dc_seed_percent *= f;
    m_noise.nodes *= f;
    m_noise.radius_seed_m *= f;
    m_noise.fold_seed_m *= f;
    m_noise.axis_seed_m *= f;
    for (const auto& r : recs) m_meas.push_back(drape_features(r));
    // Record r's residual terms are rows [m_first_term[r], m_first_term[r + 1]):
    // how many a record has depends on its measured features only.
    m_first_term.assign(m_meas.size() + 1, 0);
    for (std::size_t r = 0; r < m_meas.size(); ++r)
        m_first_term[r + 1] = m_first_term[r] + residual_terms(static_cast<int>(r), m_meas[r], m_meas[r],
                                                               std::vector<double>(m_meas[r].contours.size(), 1.0), m_noise).size();
}

cloth::DrapeSetup Evaluator::setup_for(int r, std::uint64_t seed, bool on_branch) const
{
    cloth::DrapeSetup s = m_recs[static_cast<std::size_t>(r)].setup(m_opt.grid, seed);
    s.mesh = m_opt.mesh;
    // Mixed: the odd seeds (counted from the fit's seed) start from the random mix.
    const bool random_seed = m_opt.branch == FoldBranch::Mixed && ((seed - m_opt.seed) % 2 == 1);
    const int n = on_branch && !random_seed ? branch_of(r) : 0;
    if (n > 0) return cloth::on_fold_branch(s, n, m_opt.branch_lift_m);
    cloth::DrapeSetup laid = s;
    laid.laying_load = m_opt.laying_load;
    laid.perturbation = m_opt.perturbation_m;
    return laid;
}

int Evaluator::branch_of(int r) const
{
    return m_opt.branch != FoldBranch::Random ? measured_fold_branch(m_meas[static_cast<std::size_t>(r)].node_count) : 0;
}

namespace {
bool is_bending_variable(const FitVariable& v)
{
    return v.name == "bend_Nm" || v.name == "bend_warp_Nm" || v.name == "bend_weft_Nm";
}
} // namespace

std::vector<ResidualTerm> Evaluator::prior_terms(const cloth::FabricParams& p) const
{
    std::vector<ResidualTerm> out;
    if (!m_opt.priors) return out;
    if (std::none_of(m_vars.begin(), m_vars.end(), is_bending_variable)) return out;
    const double w = p[Param::BendWarp], f = p[Param::BendWeft];
    if (!(w > 0) || !(f > 0)) return out;
    ResidualTerm a;
    a.record = -1;
    a.kind = "prior_anisotropy";
    a.simulated = std::log10(w / f);
    a.measured = 0;
    a.sigma = m_opt.prior.anisotropy_sigma_decades;
    ResidualTerm b = a;
    b.kind = "prior_bending";
    b.simulated = 0.5 * std::log10(w * f);
    b.measured = m_opt.prior.bending_centre_log10_Nm;
    b.sigma = m_opt.prior.bending_sigma_decades;
    out.push_back(a);
    out.push_back(b);
    return out;
}

double Evaluator::prior_slope(const std::string& kind, std::size_t i) const
{
    const std::string& v = m_vars[i].name;
    if (kind == "prior_anisotropy") return v == "bend_warp_Nm" ? 1.0 : v == "bend_weft_Nm" ? -1.0 : 0.0;
    if (kind == "prior_bending") return v == "bend_Nm" ? 1.0 : (v == "bend_warp_Nm" || v == "bend_weft_Nm") ? 0.5 : 0.0;
    return 0.0;
}

cloth::FabricParams Evaluator::params_at(const Eigen::VectorXd& x) const
{
    cloth::FabricParams p = m_base;
    for (std::size_t i = 0; i < m_vars.size(); ++i)
        for (Param q : m_vars[i].params)
            p[q] = std::clamp(m_vars[i].to_value(x[static_cast<Eigen::Index>(i)]), cloth::spec(q).lower, cloth::spec(q).upper);
    return p;
}

Evaluation Evaluator::evaluate(const Eigen::VectorXd& x, Start from)
{
    Evaluation e = evaluate_params(params_at(x), from);
    m_last_x = x;
    return e;
}

Evaluation Evaluator::evaluate_params(const cloth::FabricParams& p, Start from)
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    m_last_x = Eigen::VectorXd(); // not a search point (evaluate sets it after)
    const int S = std::max(1, m_opt.seeds_per_evaluation);
    const int R = static_cast<int>(m_recs.size());
    Evaluation e;
    e.sims.assign(static_cast<std::size_t>(R), std::vector<cloth::DrapeResult>(static_cast<std::size_t>(S)));
    const auto t0 = Clock::now();
    const int nthreads = std::clamp(m_opt.parallel_seeds, 1, R * S);
    parallel_for(static_cast<std::size_t>(R * S), nthreads, [&](std::size_t j) {
        const int r = static_cast<int>(j) / S, s = static_cast<int>(j) % S;
        const cloth::DrapeSetup setup = setup_for(r, m_opt.seed + static_cast<std::uint64_t>(s), true);
        const cloth::FabricParams pr = params_for_record(p, m_recs[static_cast<std::size_t>(r)]);
        cloth::RestOptions ro = m_opt.rest;
        ro.cancel = m_opt.cancel;
        ro.progress = nullptr;
        auto& out = e.sims[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
        if (from == Start::Best && m_have_states) {
            ro.max_newton = std::min(ro.max_newton, m_opt.warm_max_newton);
            out = cloth::simulate_drape_from(pr, setup, m_states[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)], ro,
                                             m_opt.model_options);
        } else {
            out = cloth::simulate_drape(pr, setup, ro, m_opt.model_options);
        }
    });
    m_sim_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
    m_simulations += static_cast<long>(R * S);
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};

    for (int r = 0; r < R; ++r) {
        std::vector<DrapeFeatures> fs;
        for (int s = 0; s < S; ++s) {
            const auto& sim = e.sims[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
            if (!sim.status.converged()) ++m_unconverged;
            fs.push_back(drape_features(sim, m_recs[static_cast<std::size_t>(r)]));
        }
        std::vector<double> closed;
        DrapeFeatures avg = average_features(fs, &closed);
        auto t = residual_terms(r, m_meas[static_cast<std::size_t>(r)], avg, closed, m_noise);
        for (auto& term : t)
            term.fitted = std::find(m_opt.channels.begin(), m_opt.channels.end(), channel_of(term.kind)) != m_opt.channels.end();
        e.terms.insert(e.terms.end(), t.begin(), t.end());
        e.features.push_back(std::move(avg));
    }
    if (m_sigma_floor.size() == e.terms.size())
        for (std::size_t i = 0; i < e.terms.size(); ++i) e.terms[i].sigma = std::max(e.terms[i].sigma, m_sigma_floor[i]);
    // After the floors (which are the records' rows'): the priors are not draws.
    const auto pr = prior_terms(p);
    e.terms.insert(e.terms.end(), pr.begin(), pr.end());
    bool comparable = true;
    if (!m_opt.term_sigmas.empty()) {
        // Given sigmas are per term of a fixed layout; a drape whose terms differ
        // (e.g. no hem seen) is not comparable on them: its chi2 is infinite, so it
        // is never the best point (a fallback to other sigmas would be another scale).
        comparable = m_opt.term_sigmas.size() == e.terms.size();
        if (comparable)
            for (std::size_t i = 0; i < e.terms.size(); ++i) e.terms[i].sigma = m_opt.term_sigmas[i];
    }
    e.chi2 = comparable ? chi_square(e.terms) : std::numeric_limits<double>::infinity();
    ++m_evaluations;
    m_last = e;
    return e;
}

DrapeFeatures Evaluator::drape_cold(int r, const cloth::FabricParams& p, std::uint64_t seed, bool on_branch, int grid, bool* at_rest,
                                    const cloth::LevelRest* start, std::vector<cloth::LevelRest>* levels) const
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    cloth::RestOptions ro = m_opt.rest;
    ro.cancel = m_opt.cancel;
    ro.progress = nullptr;
    const MeasuredDrape& rec = m_recs[static_cast<std::size_t>(r)];
    cloth::DrapeSetup setup = setup_for(r, seed, on_branch);
    if (grid > 0) setup.grid = grid;
    const cloth::DrapeResult sim = cloth::simulate_drape(params_for_record(p, rec), setup, ro, m_opt.model_options, start, levels);
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    if (at_rest) *at_rest = sim.status.converged();
    return drape_features(sim, rec);
}

void Evaluator::draw_from_flat(const Eigen::VectorXd& x, const std::string& stage, FlatDraw which)
{
    announce(stage);
    draw_flat(x, which);
    report(stage);
}

void Evaluator::draw_flat(const Eigen::VectorXd& x, FlatDraw which)
{
    const bool fine_too = which != FlatDraw::FitGrid;
    const cloth::FabricParams p = params_at(x);
    const int R = static_cast<int>(m_recs.size());
    m_cold.resize(static_cast<std::size_t>(R));
    m_cold_seeds.resize(static_cast<std::size_t>(R), 0);
    m_cold_nodes.resize(static_cast<std::size_t>(R));
    m_cold_fine.assign(static_cast<std::size_t>(R), std::nullopt); // another point's
    struct Job {
        int r;
        std::uint64_t seed;
        int grid; // 0: the fit's; or flat_check_grid
        const FlatMemo* kept = nullptr;        // drawn before at p
        const cloth::LevelRest* start = nullptr; // the finer drape's coarse level, from a kept drape
    };
    auto kept_drape = [&](int r, std::uint64_t seed, int grid) -> const FlatMemo* {
        for (const auto& m : m_flat_memo)
            if (m.r == r && m.seed == seed && m.grid == grid && m.p.values == p.values) return &m;
        return nullptr;
    };
    // A kept level rest of record r's drapes with `seed` at p on `grid`.
    auto kept_level = [&](int r, std::uint64_t seed, int grid) -> const cloth::LevelRest* {
        for (const auto& m : m_flat_memo)
            if (m.r == r && m.seed == seed && m.p.values == p.values)
                for (const auto& l : m.levels)
                    if (l.grid == grid) return &l;
        return nullptr;
    };
    std::vector<Job> jobs;
    // The finer grid's drapes first: each is the longest job (it lays the sheet
    // on the continuation's coarsest level, then refines), so the two threads
    // finish together.
    const bool finer_drapes = m_opt.flat_check_grid > m_opt.grid && m_opt.random_start_seeds > 0; // in this fit (not only this call)
    const bool fine = fine_too && finer_drapes;
    const int fine_level = cloth::continuation_level(m_opt.flat_check_grid); // 0: the finer drape has none
    // Every record's (a record fitted from the random mix has its cold_* from
    // the spread's draws, but no drape on the finer grid).
    for (int r = 0; r < R && fine; ++r) {
        const std::uint64_t seed = m_opt.seed + 1000;
        jobs.push_back({r, seed, m_opt.flat_check_grid, kept_drape(r, seed, m_opt.flat_check_grid), fine_level > 0 ? kept_level(r, seed, fine_level) : nullptr});
    }
    for (int r = 0; r < R; ++r)
        if (branch_of(r) != 0)
            for (int k = 0; k < m_opt.random_start_seeds; ++k) {
                const std::uint64_t seed = m_opt.seed + 1000 + static_cast<std::uint64_t>(k);
                jobs.push_back({r, seed, 0, kept_drape(r, seed, 0), nullptr});
            }
    if (jobs.empty()) return;
    // Those drawn before first in the list (no work), then the finer ones that
    // start from a kept level (the shortest of the finer ones) last among them.
    std::vector<FlatMemo> drawn(jobs.size());
    std::vector<std::size_t> todo;
    for (std::size_t j = 0; j < jobs.size(); ++j)
        if (jobs[j].kept) drawn[j] = *jobs[j].kept;
        else todo.push_back(j);
    std::stable_partition(todo.begin(), todo.end(), [&](std::size_t j) { return !jobs[j].start; });
    const auto t0 = Clock::now();
    const int nthreads = std::clamp(m_opt.parallel_seeds, 1, std::max(1, static_cast<int>(todo.size())));
    parallel_for(todo.size(), nthreads, [&](std::size_t t) {
        const std::size_t j = todo[t];
        const Job& job = jobs[j];
        FlatMemo& m = drawn[j];
        m.p = p;
        m.r = job.r;
        m.seed = job.seed;
        m.grid = job.grid;
        bool ok = false;
        m.drape.features = drape_cold(job.r, p, job.seed, false, job.grid, &ok, job.start, &m.levels);
        m.drape.at_rest = ok;
    });
    if (!todo.empty()) m_sim_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
    m_simulations += static_cast<long>(todo.size());
    for (int r = 0; r < R; ++r) {
        std::vector<DrapeFeatures> cold;
        for (std::size_t j = 0; j < jobs.size(); ++j) {
            if (jobs[j].r != r) continue;
            if (jobs[j].grid > 0) m_cold_fine[static_cast<std::size_t>(r)] = drawn[j].drape;
            else cold.push_back(drawn[j].drape.features);
        }
        if (cold.empty()) continue;
        std::vector<double> closed;
        m_cold[static_cast<std::size_t>(r)] = average_features(cold, &closed);
        m_cold_seeds[static_cast<std::size_t>(r)] = static_cast<int>(cold.size());
        m_cold_nodes[static_cast<std::size_t>(r)].clear();
        for (const auto& c : cold) m_cold_nodes[static_cast<std::size_t>(r)].push_back(c.node_count);
    }
    // Keep this point's new drapes (the kept ones stay), dropping the oldest
    // points' beyond kFlatMemoPoints; of their level rests only the one a finer
    // drape starts from (its seed's, on the finer grid's coarse level).
    for (std::size_t j : todo) {
        FlatMemo& m = drawn[j];
        std::erase_if(m.levels, [&](const cloth::LevelRest& l) { return !finer_drapes || m.seed != m_opt.seed + 1000 || l.grid != fine_level; });
        m_flat_memo.push_back(std::move(m));
    }
    for (const Job& job : jobs)
        if (job.start && !job.kept) ++m_flat_levels_reused;
    std::vector<cloth::FabricParams> points;
    for (auto it = m_flat_memo.rbegin(); it != m_flat_memo.rend(); ++it)
        if (std::none_of(points.begin(), points.end(), [&](const cloth::FabricParams& q) { return q.values == it->p.values; })) points.push_back(it->p);
    if (points.size() > kFlatMemoPoints) {
        points.resize(kFlatMemoPoints);
        std::erase_if(m_flat_memo, [&](const FlatMemo& m) {
            return std::none_of(points.begin(), points.end(), [&](const cloth::FabricParams& q) { return q.values == m.p.values; });
        });
    }
}

void Evaluator::calibrate_spread(const Eigen::VectorXd& x, int extra)
{
    const cloth::FabricParams p = params_at(x);
    const int S = std::max(1, m_opt.seeds_per_evaluation);
    const int R = static_cast<int>(m_recs.size());
    std::vector<std::vector<double>> values; // [term][draw]
    m_cold.assign(static_cast<std::size_t>(R), {});
    m_cold_seeds.assign(static_cast<std::size_t>(R), 0);
    m_cold_nodes.assign(static_cast<std::size_t>(R), {});
    m_cold_fine.assign(static_cast<std::size_t>(R), std::nullopt);
    // The drapes, all records' at once on the fit's threads (each is
    // independent): per record `extra` on the fit's branch.
    struct Job {
        int r;
        std::uint64_t seed;
    };
    // Given sigmas (a tied refit takes the free fit's) replace the calibrated
    // ones, so the branch's drapes are only drawn where they are also the
    // report's cold_* (the fit's branch is the random mix).
    const bool sigmas_given = !m_opt.term_sigmas.empty();
    auto branch_draws = [&](int r) { return sigmas_given && branch_of(r) != 0 ? 0 : extra; };
    std::vector<Job> jobs;
    for (int r = 0; r < R; ++r)
        for (int k = 0; k < branch_draws(r); ++k) jobs.push_back({r, m_opt.seed + 1000 + static_cast<std::uint64_t>(k)});
    std::vector<DrapeFeatures> drawn(jobs.size());
    const auto t0 = Clock::now();
    const int nthreads = std::clamp(m_opt.parallel_seeds, 1, std::max(1, static_cast<int>(jobs.size())));
    parallel_for(jobs.size(), nthreads, [&](std::size_t j) { drawn[j] = drape_cold(jobs[j].r, p, jobs[j].seed, true); });
    m_sim_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
    m_simulations += static_cast<long>(jobs.size());
    std::size_t next = 0;
    for (int r = 0; r < R; ++r) {
        const auto& meas = m_meas[static_cast<std::size_t>(r)];
        std::vector<DrapeFeatures> draws, cold;
        for (const auto& sim : m_best.sims[static_cast<std::size_t>(r)]) draws.push_back(drape_features(sim, m_recs[static_cast<std::size_t>(r)]));
        // The spread is measured on the fit's branch (the record and the fit's
        // drapes share its fold count); `cold_*` report the preset draped from
        // the random mix, as `drape predict` does - the same drapes when the fit
        // itself starts from the random mix (draw_from_flat draws the others).
        const int mine = branch_draws(r);
        for (int k = 0; k < mine; ++k) draws.push_back(std::move(drawn[next++]));
        if (branch_of(r) == 0) cold.assign(draws.end() - mine, draws.end());
        if (!cold.empty()) {
            std::vector<double> closed;
            m_cold[static_cast<std::size_t>(r)] = average_features(cold, &closed);
            m_cold_seeds[static_cast<std::size_t>(r)] = static_cast<int>(cold.size());
            for (const auto& c : cold) m_cold_nodes[static_cast<std::size_t>(r)].push_back(c.node_count);
        }
        const std::size_t base = m_first_term[static_cast<std::size_t>(r)];
        for (const auto& d : draws) {
            std::vector<double> closed;
            for (const auto& c : d.contours) closed.push_back(c.closed ? 1.0 : 0.0);
            const auto t = residual_terms(r, meas, d, closed, m_noise);
            if (values.size() < base + t.size()) values.resize(base + t.size());
            for (std::size_t i = 0; i < t.size(); ++i) values[base + i].push_back(t[i].simulated);
        }
    }
    const double both = std::sqrt(1.0 + 1.0 / S);
    m_sigma_floor.assign(values.size(), 0.0);
    const std::vector<ResidualTerm>& kinds = m_best.terms;
    for (std::size_t i = 0; i < values.size() && i < kinds.size(); ++i) {
        const auto& v = values[i];
        if (v.size() < 2 || kinds[i].kind == "closure") continue;
        double m = 0, ss = 0;
        for (double x0 : v) m += x0 / static_cast<double>(v.size());
        for (double x0 : v) ss += (x0 - m) * (x0 - m);
        const double sd = std::sqrt(ss / static_cast<double>(v.size() - 1));
        const auto r = static_cast<std::size_t>(kinds[i].record);
        const double corr = channel_of(kinds[i].kind) == "contours" ? std::sqrt(static_cast<double>(m_meas[r].contours.size())) : 1.0;
        m_sigma_floor[i] = both * corr * sd;
    }
    m_spread_calibrated = true;
    const Evaluation e = evaluate(x, Start::Best);
    m_best = e;
    m_best_x = x;
}

double Evaluator::objective_from(const Eigen::VectorXd& x, const std::vector<std::vector<cloth::Positions>>& states, const std::string& stage)
{
    const std::size_t S = static_cast<std::size_t>(std::max(1, m_opt.seeds_per_evaluation));
    bool fits = states.size() == m_recs.size();
    for (const auto& rs : states) fits = fits && rs.size() == S;
    if (!fits) throw ParameterError("fit: warm start states do not match the records and seeds");
    // objective() replaces m_states (with the evaluation's own) when it takes the best point.
    auto given = states; // copied before anything is moved: a failed copy leaves the evaluator as it was
    auto saved = std::move(m_states);
    const bool had = m_have_states;
    const double best_before = m_best.chi2;
    m_states = std::move(given);
    m_have_states = true;
    auto restore = [&] {
        m_states = std::move(saved);
        m_have_states = had;
    };
    double f = 0;
    try {
        f = objective(x, Start::Best, stage);
    } catch (...) {
        restore();
        throw;
    }
    if (!(m_best.chi2 < best_before)) restore();
    return f;
}

void Evaluator::set_best(const Evaluation& e, const Eigen::VectorXd& x)
{
    m_best = e;
    m_best_x = x;
    m_states.assign(e.sims.size(), {});
    for (std::size_t r = 0; r < e.sims.size(); ++r)
        for (const auto& s : e.sims[r]) m_states[r].push_back(s.x);
    m_have_states = true;
}

double Evaluator::objective(const Eigen::VectorXd& x, Start from, const std::string& stage)
{
    Evaluation e = evaluate(x, from);
    // A drape that did not come to rest is no drape of the model: its features
    // describe a state the preset does not rest in, so it cannot replace a best
    // point that is at rest, however low its chi2. (On DL-A05 a warm re-solve
    // ran to the iteration cap, became the best point at a lower chi2 and the
    // fit went on from its state.)
    const bool eligible = e.at_rest() || !m_best.at_rest();
    if (e.chi2 < m_best.chi2 && eligible) set_best(e, x);
    report(stage);
    return eligible ? e.chi2 : std::max(e.chi2, m_best.chi2);
}

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
} // namespace

bool slopes_agree(double full, double half, double floor)
{
    return std::abs(full - half) <= 0.1 * std::max(std::abs(full), std::abs(half)) + floor;
}

Eigen::MatrixXd Evaluator::jacobian(const Eigen::VectorXd& x, const Evaluation& e, bool resolves)
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    ++m_jacobians;
    const cloth::FabricParams p = params_at(x);
    const int S = std::max(1, m_opt.seeds_per_evaluation);
    const int R = static_cast<int>(m_recs.size());
    const int n = static_cast<int>(m_vars.size());
    const Eigen::Index rows = static_cast<Eigen::Index>(e.terms.size());
    Eigen::MatrixXd J = Eigen::MatrixXd::Zero(rows, n);
    if (static_cast<int>(e.sims.size()) != R) return J;

    // Which variables the sensitivities serve: every parameter of the group
    // nonzero and inside its bounds (clamped coordinates do not move anything),
    // and every drape at rest.
    std::vector<char> exact(static_cast<std::size_t>(n), e.at_rest() ? 1 : 0);
    for (int i = 0; i < n; ++i)
        for (Param q : m_vars[static_cast<std::size_t>(i)].params)
            if (!(p[q] > cloth::spec(q).lower) || !(p[q] < cloth::spec(q).upper) || !cloth::spec(q).affects_statics) exact[static_cast<std::size_t>(i)] = 0;
    // A linear coordinate at a lower bound of 0 switches an effect on (a radius, a
    // buckling length) that enters as its square or higher: its slope there is 0
    // (a start at 0 is stored as 1e-300), and a small difference sees nothing, so
    // the search could never leave 0. The secant over a fifth of the range (6 mm of
    // a 30 mm radius) says whether switching it on helps.
    auto at_switch = [&](int i) {
        const auto& v = m_vars[static_cast<std::size_t>(i)];
        return !v.log_scale && v.lower == 0 && x[i] <= 1e-6 * (v.upper - v.lower);
    };
    for (int i = 0; i < n; ++i)
        if (at_switch(i)) exact[static_cast<std::size_t>(i)] = 0;

    // Coordinate step of the metric's central difference along dx/dc: the
    // first-order path is linear, so the step only has to be small against the
    // metrics' own kinks (a shadow vertex crossing the rim).
    auto delta = [&](int i) {
        const auto& v = m_vars[static_cast<std::size_t>(i)];
        return v.log_scale ? 1e-3 : 1e-3 * (v.upper - v.lower);
    };
    // features[r][s][4 i + (0 up, 1 down, 2 half up, 3 half down)]: the difference
    // is taken at the step and at half of it, and a row whose two slopes disagree
    // has no derivative for that column (below).
    std::vector<std::vector<std::vector<DrapeFeatures>>> feats(static_cast<std::size_t>(R),
        std::vector<std::vector<DrapeFeatures>>(static_cast<std::size_t>(S), std::vector<DrapeFeatures>(static_cast<std::size_t>(4 * n))));
    std::vector<Param> qs;
    for (int i = 0; i < n; ++i)
        if (exact[static_cast<std::size_t>(i)])
            for (Param q : m_vars[static_cast<std::size_t>(i)].params) qs.push_back(q);
    bool sens_ok = !qs.empty();
    if (sens_ok) {
        const int nthreads = std::clamp(m_opt.parallel_seeds, 1, R * S);
        try {
            parallel_for(static_cast<std::size_t>(R * S), nthreads, [&](std::size_t j) {
                const int r = static_cast<int>(j) / S, s = static_cast<int>(j) % S;
                const auto& rec = m_recs[static_cast<std::size_t>(r)];
                const auto& sim = e.sims[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
                const cloth::DrapeSetup setup = setup_for(r, m_opt.seed + static_cast<std::uint64_t>(s), true);
                const cloth::FabricParams pr = params_for_record(p, rec);
                const cloth::Material mat(pr);
                const auto sens = cloth::rest_sensitivities(mat, setup, sim.x, qs, m_opt.model_options);
                auto sys = cloth::make_drape_system(mat, setup, m_opt.model_options);
                std::size_t k = 0;
                for (int i = 0; i < n; ++i) {
                    if (!exact[static_cast<std::size_t>(i)]) continue;
                    const auto& v = m_vars[static_cast<std::size_t>(i)];
                    cloth::Positions dxdc = cloth::Positions::Zero(sim.x.rows(), 3);
                    for (Param q : v.params) {
                        // d value / d coordinate: value ln 10 on a log scale.
                        const double dv = v.log_scale ? pr[q] * std::log(10.0) : 1.0;
                        dxdc += dv * sens[k++].dx;
                    }
                    const double d = delta(i);
                    auto& f = feats[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
                    const double steps[4] = {d, -d, 0.5 * d, -0.5 * d};
                    for (int m = 0; m < 4; ++m) {
                        sys->x = sim.x + steps[m] * dxdc;
                        f[static_cast<std::size_t>(4 * i + m)] = drape_features(cloth::measure_drape(*sys, setup), rec);
                    }
                }
            });
        } catch (const drape::Error&) {
            sens_ok = false; // not a stable rest state: differences of re-solves below
        }
        if (sens_ok) {
            m_factorisations += R * S;
            m_back_substitutions += static_cast<long>(R * S) * static_cast<long>(qs.size());
        }
    }
    const std::vector<std::size_t>& first = m_first_term;
    // The prior rows: linear in the log10 coordinates.
    for (std::size_t row = first.back(); row < e.terms.size(); ++row)
        for (int i = 0; i < n; ++i)
            J(static_cast<Eigen::Index>(row), i) = prior_slope(e.terms[row].kind, static_cast<std::size_t>(i)) / e.terms[row].sigma;
    if (first.back() + prior_terms(p).size() != e.terms.size()) return J; // not this evaluator's terms
    // The closure rows count seeds whose slice closed: no derivative (a flip
    // between x + d and x - d would read as a slope of thousands).
    auto keep_row = [&](std::size_t k) {
        return e.terms[k].smooth && e.terms[k].fitted && e.terms[k].sigma > 0 && e.terms[k].kind != "closure";
    };
    for (int i = 0; i < n; ++i) {
        if (sens_ok && exact[static_cast<std::size_t>(i)]) {
            const double d = delta(i);
            for (int r = 0; r < R; ++r) {
                // The seed-averaged terms at the four points of the column.
                std::vector<ResidualTerm> t[4];
                std::vector<double> closed[4];
                const auto& mr = m_meas[static_cast<std::size_t>(r)];
                for (int k = 0; k < 4; ++k) {
                    std::vector<DrapeFeatures> at;
                    for (int s = 0; s < S; ++s) at.push_back(feats[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)][static_cast<std::size_t>(4 * i + k)]);
                    t[k] = residual_terms(r, mr, average_features(at, &closed[k]), closed[k], m_noise);
                }
                const std::size_t count = first[static_cast<std::size_t>(r) + 1] - first[static_cast<std::size_t>(r)];
                if (t[0].size() != count || t[1].size() != count || t[2].size() != count || t[3].size() != count)
                    continue; // rows would not line up: leave the column's rows at 0
                for (std::size_t k = 0; k < count; ++k) {
                    const std::size_t row = first[static_cast<std::size_t>(r)] + k;
                    // A depth whose slice closed for another set of seeds on the two
                    // sides averages other drapes: no derivative there.
                    if (!same_closure(closed[0], closed[1], mr, e.terms[row]) || !same_closure(closed[2], closed[3], mr, e.terms[row])) continue;
                    if (!keep_row(row)) continue;
                    bool finite = true;
                    for (int q = 0; q < 4; ++q) finite = finite && std::isfinite(t[q][k].simulated);
                    if (!finite) continue;
                    const double full = (t[0][k].simulated - t[1][k].simulated) / (2 * d) / e.terms[row].sigma;
                    const double half = (t[2][k].simulated - t[3][k].simulated) / d / e.terms[row].sigma;
                    // A feature that jumps between the points (a selection that
                    // switches: a ray's outermost crossing, a vertex entering a
                    // window) has no derivative for this column: 0, as for a closure
                    // flip, and counted. A kink between them (a minimum's argmin
                    // switching within 1e-3 decades) is dropped too: rare, and a
                    // zero only widens the interval.
                    // The floor: 0.05 sigma per thousand steps (a decade of a
                    // log coordinate, the range of a linear one).
                    if (!slopes_agree(full, half, 0.05 * 1e-3 / d)) {
                        ++m_jacobian_jumps;
                        continue;
                    }
                    J(static_cast<Eigen::Index>(row), i) = full;
                }
            }
            continue;
        }
        if (!resolves) continue;
        // A one-sided difference of warm re-solves, into the box. From a rest state,
        // a re-solve that did not come to rest is no drape of the model: its
        // difference would be a slope of the solver's path. Then the other side;
        // failing both, the column stays 0 (the parameter reads as not seen by the
        // data, and its interval says so). Before any drape at rest (e not at rest)
        // the differences are all the search has, and are kept as they are.
        const auto& v = m_vars[static_cast<std::size_t>(i)];
        double h = v.log_scale ? 0.05 : 0.02 * (v.upper - v.lower);
        if (at_switch(i)) h = 0.2 * (v.upper - v.lower); // see at_switch
        Eigen::VectorXd xp = x;
        if (x[i] + h > v.upper) h = -h;
        xp[i] = x[i] + h;
        Evaluation ep = evaluate(xp, Start::Best);
        report("jacobian");
        if (e.at_rest() && !ep.at_rest() && x[i] - h >= v.lower && x[i] - h <= v.upper) {
            h = -h;
            xp[i] = x[i] + h;
            ep = evaluate(xp, Start::Best);
            report("jacobian");
        }
        if (e.at_rest() && !ep.at_rest()) continue;
        for (std::size_t k = 0; k < first.back() && k < e.terms.size() && k < ep.terms.size(); ++k)
            if (keep_row(k) && std::isfinite(ep.terms[k].simulated) && std::isfinite(e.terms[k].simulated))
                J(static_cast<Eigen::Index>(k), i) = (ep.terms[k].simulated - e.terms[k].simulated) / h / e.terms[k].sigma;
    }
    return J;
}

namespace {
/// Whether a record's measurement model takes the instrument effect out of its contours.
bool removed_by_measurement_model(const EffectSpec& sp, const MeasuredDrape& rec)
{
    if (sp.kind == EffectKind::ProfilerAxis) return rec.recentre_contours || rec.untilt_contours;
    if (sp.kind == EffectKind::ProfilerTilt) return rec.untilt_contours;
    return false;
}
} // namespace

std::vector<EffectSignature> Evaluator::effect_signatures(const Eigen::VectorXd& x, const Evaluation& e)
{
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    const auto& lib = effect_library();
    const cloth::FabricParams p = params_at(x);
    const int S = std::max(1, m_opt.seeds_per_evaluation);
    const int R = static_cast<int>(m_recs.size());
    const Eigen::Index rows = static_cast<Eigen::Index>(e.terms.size());
    std::vector<EffectSignature> out(lib.size());
    const bool all_at_rest = static_cast<int>(e.sims.size()) == R && e.at_rest();
    // Which effects can be made here, and their columns.
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
    // Features of every (record, seed) with each effect on: [r][s][effect][column].
    std::vector<std::vector<std::vector<std::vector<DrapeFeatures>>>> on(
        static_cast<std::size_t>(R), std::vector<std::vector<std::vector<DrapeFeatures>>>(
                                         static_cast<std::size_t>(S), std::vector<std::vector<DrapeFeatures>>(lib.size())));
    std::vector<std::vector<DrapeFeatures>> off(static_cast<std::size_t>(R), std::vector<DrapeFeatures>(static_cast<std::size_t>(S)));
    constexpr double kRel = 1e-3;   // relative change of a parameter along its dx/d ln p (first order: any small step)
    constexpr double kScale = 1e-3; // scale error
    constexpr double kShift = 1e-4; // [m] axis shift
    constexpr double kTilt = 1e-3;  // [rad] axis tilt
    constexpr double kDepth = 1e-4; // [m] the cuts' depth datum
    constexpr double kLin = 1e-3;   // fraction of a specimen effect's switched-on size along its response
    long resolves = 0;
    std::atomic<bool> parameter_failed{false};
    std::vector<std::atomic<char>> switch_failed(lib.size());
    for (auto& f : switch_failed) f = 0;
    const auto t0 = Clock::now();
    const int nthreads = std::clamp(m_opt.parallel_seeds, 1, R * S);
    if (all_at_rest) {
        std::mutex count_mutex;
        parallel_for(static_cast<std::size_t>(R * S), nthreads, [&](std::size_t j) {
            const int r = static_cast<int>(j) / S, s = static_cast<int>(j) % S;
            const auto& rec = m_recs[static_cast<std::size_t>(r)];
            const auto& sim = e.sims[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
            const cloth::DrapeSetup setup = setup_for(r, m_opt.seed + static_cast<std::uint64_t>(s), true);
            const cloth::FabricParams pr = params_for_record(p, rec);
            const cloth::Material mat(pr);
            auto sys = cloth::make_drape_system(mat, setup, m_opt.model_options);
            auto measure = [&](const cloth::Positions& X) {
                sys->x = X;
                return drape_features(cloth::measure_drape(*sys, setup), rec);
            };
            off[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)] = measure(sim.x);
            std::vector<cloth::RestSensitivity> sens;
            std::vector<Param> qs;
            for (Param q : sens_params)
                if (pr[q] > 0) qs.push_back(q);
            // The specimen's effects: the set-up changed along x, then y (responses
            // on the same factorisation as the parameters').
            std::vector<cloth::DrapeSetup> changed;
            std::vector<std::size_t> changed_first(lib.size(), 0);
            for (std::size_t k = 0; k < lib.size(); ++k)
                if (out[k].available && lib[k].kind == EffectKind::Specimen) {
                    changed_first[k] = changed.size();
                    for (int c = 0; c < 2; ++c) {
                        cloth::DrapeSetup su = setup;
                        su.density_gradient[c] = lib[k].density_gradient;
                        changed.push_back(su);
                    }
                }
            cloth::RestResponses resp;
            bool sens_ok = true;
            try {
                if (!qs.empty() || !changed.empty()) resp = cloth::rest_responses(mat, setup, sim.x, qs, changed, m_opt.model_options);
                sens = std::move(resp.params);
            } catch (const drape::Error&) {
                sens_ok = false; // not a stable rest state: no parameter signatures (the others need no Hessian)
                parameter_failed = true;
            }
            auto& mine = on[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)];
            long my_resolves = 0;
            for (std::size_t k = 0; k < lib.size(); ++k) {
                if (!out[k].available) continue;
                const EffectSpec& sp = lib[k];
                switch (sp.kind) {
                case EffectKind::Parameter: {
                    if (!sens_ok) break;
                    cloth::Positions dx = cloth::Positions::Zero(sim.x.rows(), 3);
                    for (std::size_t m = 0; m < sp.params.size(); ++m)
                        for (std::size_t i = 0; i < qs.size(); ++i)
                            if (qs[i] == sp.params[m]) dx += effect_weight(sp, m) * pr[qs[i]] * sens[i].dx; // d x / d ln p
                    mine[k] = {measure(sim.x + kRel * dx)};
                    break;
                }
                case EffectKind::Switch: {
                    cloth::FabricParams q = pr;
                    for (Param w : sp.params) q[w] = sp.on_value;
                    cloth::DrapeSetup su = setup;
                    su.disc_grip = su.disc_grip || sp.disc_grip;
                    cloth::ModelOptions mo = m_opt.model_options;
                    if (sp.vertex_contact) mo.edge_contact = false;
                    if (sp.self_contact) mo.self_collision = true;
                    cloth::RestOptions ro = m_opt.rest;
                    ro.cancel = m_opt.cancel;
                    ro.progress = nullptr;
                    const cloth::DrapeResult d = cloth::simulate_drape_from(cloth::Material(q), su, sim.x, ro, mo);
                    ++my_resolves;
                    if (!d.status.converged()) switch_failed[k] = 1; // not at rest: no signature
                    mine[k] = {drape_features(d, rec)};
                    break;
                }
                case EffectKind::Specimen: { // the set-up's response along x, then y, a kLin of the way
                    if (!sens_ok) break;
                    for (int c = 0; c < 2; ++c) mine[k].push_back(measure(sim.x + kLin * resp.setups[changed_first[k] + static_cast<std::size_t>(c)]));
                    break;
                }
                case EffectKind::CameraScale: // the photos: every length, the hem's height too
                    mine[k] = {measure(sim.x * (1 + kScale))};
                    break;
                case EffectKind::ProfilerScale: { // the laser: radii only (the depths are the profiler's own setting)
                    cloth::Positions X = sim.x;
                    X.leftCols(2) *= 1 + kScale;
                    mine[k] = {measure(X)};
                    break;
                }
                case EffectKind::ProfilerAxis: {
                    cloth::Positions X = sim.x, Y = sim.x;
                    X.col(0).array() += kShift;
                    Y.col(1).array() += kShift;
                    mine[k] = {measure(X), measure(Y)};
                    break;
                }
                case EffectKind::ProfilerDepth: { // a cut declared at depth d taken at d + delta: the plane z = -d meets the drape moved up by delta
                    cloth::Positions X = sim.x;
                    X.col(2).array() += kDepth;
                    mine[k] = {measure(X)};
                    break;
                }
                case EffectKind::ProfilerTilt: { // a cut at depth d (z = -d) lands d tan(t) sideways
                    cloth::Positions X = sim.x, Y = sim.x;
                    X.col(0) -= kTilt * sim.x.col(2);
                    Y.col(1) -= kTilt * sim.x.col(2);
                    mine[k] = {measure(X), measure(Y)};
                    break;
                }
                }
            }
            std::lock_guard lock(count_mutex);
            resolves += my_resolves;
        });
        m_simulations += resolves;
        m_sim_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
        long specimen_columns = 0;
        for (std::size_t k = 0; k < lib.size(); ++k)
            if (out[k].available && lib[k].kind == EffectKind::Specimen) specimen_columns += 2;
        if ((!sens_params.empty() || specimen_columns > 0) && !parameter_failed) {
            m_factorisations += R * S;
            m_back_substitutions += static_cast<long>(R * S) * (static_cast<long>(sens_params.size()) + specimen_columns);
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
    if (m_opt.cancel && m_opt.cancel->load()) throw CancelledFit{};
    const std::vector<std::size_t>& first = m_first_term;
    if (first.back() + prior_terms(params_at(x)).size() != e.terms.size()) return out;
    auto photo_row = [](const std::string& kind) { return kind == "dc" || kind == "hem"; };
    for (std::size_t k = 0; k < lib.size() && all_at_rest; ++k) {
        auto& sig = out[k];
        if (!sig.available) continue;
        const EffectSpec& sp = lib[k];
        const double unit = sp.kind == EffectKind::Parameter ? kRel : sp.kind == EffectKind::Switch ? 1.0
                            : sp.kind == EffectKind::Specimen ? kLin * sp.density_gradient
                            : sp.kind == EffectKind::ProfilerAxis                                 ? kShift
                            : sp.kind == EffectKind::ProfilerTilt                                 ? kTilt
                            : sp.kind == EffectKind::ProfilerDepth                                ? kDepth
                                                                                                  : kScale;
        for (Eigen::Index c = 0; c < sig.columns.cols(); ++c)
            for (int r = 0; r < R; ++r) {
                std::vector<DrapeFeatures> up, base;
                for (int s = 0; s < S; ++s) {
                    up.push_back(on[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)][k][static_cast<std::size_t>(c)]);
                    base.push_back(off[static_cast<std::size_t>(r)][static_cast<std::size_t>(s)]);
                }
                std::vector<double> cu, cb;
                const DrapeFeatures au = average_features(up, &cu), ab = average_features(base, &cb);
                const auto& mr = m_meas[static_cast<std::size_t>(r)];
                const auto tu = residual_terms(r, mr, au, cu, m_noise), tb = residual_terms(r, mr, ab, cb, m_noise);
                const std::size_t count = first[static_cast<std::size_t>(r) + 1] - first[static_cast<std::size_t>(r)];
                if (tu.size() != count || tb.size() != count) continue;
                for (std::size_t i = 0; i < tu.size() && i < tb.size(); ++i) {
                    const std::size_t row = first[static_cast<std::size_t>(r)] + i;
                    const auto& t = e.terms[row];
                    if (!t.smooth || !t.fitted || !(t.sigma > 0) || t.kind == "closure") continue;
                    if (!same_closure(cu, cb, mr, t)) continue;
                    // The instruments act on their own channels only.
                    if (sp.kind == EffectKind::CameraScale && !photo_row(t.kind)) continue;
                    if ((sp.kind == EffectKind::ProfilerScale || sp.kind == EffectKind::ProfilerAxis || sp.kind == EffectKind::ProfilerTilt ||
                         sp.kind == EffectKind::ProfilerDepth) &&
                        photo_row(t.kind))
                        continue;
                    if (removed_by_measurement_model(sp, m_recs[static_cast<std::size_t>(r)])) continue;
                    if (!std::isfinite(tu[i].simulated) || !std::isfinite(tb[i].simulated)) continue;
                    sig.columns(static_cast<Eigen::Index>(row), c) = (tu[i].simulated - tb[i].simulated) / unit / t.sigma;
                }
            }
    }
    return out;
}

double Evaluator::elapsed_s() const { return std::chrono::duration<double>(Clock::now() - m_t0).count(); }

void Evaluator::report(const std::string& stage)
{
    if (m_evaluations > m_traced) {
        m_traced = m_evaluations;
        FitTraceEntry t;
        t.evaluation = m_evaluations;
        t.stage = stage;
        t.chi2 = m_last.chi2;
        t.best_chi2 = m_best.chi2;
        t.coords.assign(m_last_x.data(), m_last_x.data() + m_last_x.size());
        t.elapsed_s = std::chrono::duration<double>(Clock::now() - m_t0).count();
        m_trace.push_back(std::move(t));
    }
    progress(stage, false);
}

void Evaluator::announce(const std::string& stage) { progress(stage, true); }

void Evaluator::progress(const std::string& stage, bool starting)
{
    if (!m_opt.progress) return;
    FitProgress p;
    p.stage = stage;
    p.starting = starting;
    p.evaluation = m_evaluations;
    p.planned = m_planned;
    p.best_chi2 = m_best.chi2;
    p.simulations = m_simulations;
    p.unconverged = m_unconverged;
    p.elapsed_s = std::chrono::duration<double>(Clock::now() - m_t0).count();
    p.last_coords.assign(m_last_x.data(), m_last_x.data() + m_last_x.size());
    m_opt.progress(p);
}

} // namespace drape::estimate::detail
