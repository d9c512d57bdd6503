#include "engine/estimate/detail/evaluator.hpp"

#include "engine/core/error.hpp"
#include "engine/core/parallel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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
    m_work.simulation_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
    m_work.simulations += static_cast<long>(R * S);
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
    ++m_work.evaluations;
    m_last = e;
    return e;
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
    m_work.simulation_seconds += std::chrono::duration<double>(Clock::now() - t0).count() * nthreads;
    m_work.simulations += static_cast<long>(jobs.size());
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

double Evaluator::objective_from(const Eigen::VectorXd& x, const std::vector<std::vector<cloth::Positions>>& states, Stage stage)
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

double Evaluator::objective(const Eigen::VectorXd& x, Start from, Stage stage)
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

double Evaluator::elapsed_s() const { return std::chrono::duration<double>(Clock::now() - m_t0).count(); }

void Evaluator::report(Stage stage)
{
    if (m_work.evaluations > m_traced) {
        m_traced = m_work.evaluations;
        FitTraceEntry t;
        t.evaluation = m_work.evaluations;
        t.stage = to_string(stage);
        t.chi2 = m_last.chi2;
        t.best_chi2 = m_best.chi2;
        t.coords.assign(m_last_x.data(), m_last_x.data() + m_last_x.size());
        t.elapsed_s = std::chrono::duration<double>(Clock::now() - m_t0).count();
        m_trace.push_back(std::move(t));
    }
    progress(stage, false);
}

WorkCounters Evaluator::work() const
{
    WorkCounters w = m_work;
    w.wall_seconds = elapsed_s();
    return w;
}

void Evaluator::announce(Stage stage) { progress(stage, true); }

void Evaluator::progress(Stage stage, bool starting)
{
    if (!m_opt.progress) return;
    FitProgress p;
    p.stage = to_string(stage);
    p.stage_id = stage;
    p.starting = starting;
    p.evaluation = m_work.evaluations;
    p.planned = m_planned;
    p.best_chi2 = m_best.chi2;
    p.simulations = m_work.simulations;
    p.unconverged = m_unconverged;
    p.elapsed_s = std::chrono::duration<double>(Clock::now() - m_t0).count();
    p.last_coords.assign(m_last_x.data(), m_last_x.data() + m_last_x.size());
    m_opt.progress(p);
}

} // namespace drape::estimate::detail
