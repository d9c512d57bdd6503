#include "engine/estimate/objective.hpp"

#include "engine/core/error.hpp"

#include <algorithm>
#include <cmath>

namespace drape::estimate {

using cloth::Param;

ModelVariant parse_model_variant(const std::string& name)
{
    if (name == "baseline") return ModelVariant::Baseline;
    if (name == "stiffening") return ModelVariant::Stiffening;
    if (name == "softening") return ModelVariant::Softening;
    if (name == "full") return ModelVariant::Full;
    if (name == "buckling") return ModelVariant::Buckling;
    if (name == "peaking") return ModelVariant::Peaking;
    if (name == "slack") return ModelVariant::Slack;
    throw ParameterError("model: '" + name + "' is not one of baseline, stiffening, softening, full, buckling, peaking, slack");
}

std::string to_string(ModelVariant v)
{
    switch (v) {
    case ModelVariant::Baseline: return "baseline";
    case ModelVariant::Stiffening: return "stiffening";
    case ModelVariant::Softening: return "softening";
    case ModelVariant::Full: return "full";
    case ModelVariant::Buckling: return "buckling";
    case ModelVariant::Peaking: return "peaking";
    case ModelVariant::Slack: return "slack";
    }
    return "baseline";
}

std::vector<FitVariable> fit_variables(ModelVariant v, bool tie_bending)
{
    // The fit ranges are the parameter table's (cloth/params.cpp says why
    // each is what a drape test can tell apart). Log-scaled parameters are
    // searched in log10; the radii linearly, so 0 (the seed's linear bending)
    // stays reachable.
    std::vector<FitVariable> out;
    auto add = [&](Param p) {
        const auto& s = cloth::spec(p);
        FitVariable f;
        f.name = std::string(s.key);
        f.params = {p};
        f.log_scale = s.log_scale;
        f.lower = s.log_scale ? std::log10(s.fit_lower) : s.fit_lower;
        f.upper = s.log_scale ? std::log10(s.fit_upper) : s.fit_upper;
        out.push_back(std::move(f));
    };
    add(Param::BendWarp);
    if (tie_bending) {
        out.back().name = "bend_Nm";
        out.back().params.push_back(Param::BendWeft);
    } else {
        add(Param::BendWeft);
    }
    add(Param::Shear);
    if (v == ModelVariant::Stiffening || v == ModelVariant::Full) add(Param::BendStiffeningRadius);
    if (v == ModelVariant::Softening) add(Param::BendSofteningRadius);
    if (v == ModelVariant::Buckling) add(Param::BucklingLength);
    if (v == ModelVariant::Peaking) add(Param::BendPeakRadius);
    if (v == ModelVariant::Slack) add(Param::CompressionSlack);
    if (v == ModelVariant::Full) {
        add(Param::StretchWarp);
        add(Param::StretchWeft);
    }
    return out;
}

double NoiseModel::contour_sigma(double floor_m, int points) const
{
    const double lab = laser_m / std::sqrt(std::max(1, points));
    return std::sqrt(lab * lab + floor_m * floor_m);
}

std::vector<ResidualTerm> residual_terms(int record, const DrapeFeatures& meas, const DrapeFeatures& sim,
                                         const std::vector<double>& closed_fraction, const NoiseModel& noise)
{
    std::vector<ResidualTerm> out;
    auto add = [&](std::string kind, double s, double m, double sigma, double depth = 0, int k = 0, bool smooth = true) {
        ResidualTerm t;
        t.record = record;
        t.kind = std::move(kind);
        t.simulated = s;
        t.measured = m;
        t.sigma = sigma;
        t.depth_m = depth;
        t.harmonic = k;
        t.smooth = smooth;
        out.push_back(t);
    };
    if (std::isfinite(meas.drape_coefficient_percent))
        add("dc", sim.drape_coefficient_percent, meas.drape_coefficient_percent,
            std::hypot(noise.dc_lab_percent, noise.dc_seed_percent));
    if (meas.node_count >= 0) add("nodes", sim.node_count, meas.node_count, noise.nodes, 0, 0, false);
    if (std::isfinite(meas.hem_min_z) && std::isfinite(sim.hem_min_z)) add("hem", sim.hem_min_z, meas.hem_min_z, noise.hem_m);
    for (std::size_t d = 0; d < meas.contours.size(); ++d) {
        const ContourFeatures& m = meas.contours[d];
        ContourFeatures missing;
        missing.depth_m = m.depth_m;
        const ContourFeatures& s = d < sim.contours.size() ? sim.contours[d] : missing;
        const double cf = d < closed_fraction.size() ? closed_fraction[d] : 0.0;
        // A measured cut that closes must close in the model too: the missing
        // fraction of seeds, with 10 % of them worth one sigma.
        add("closure", 1.0 - cf, 0.0, 0.1, m.depth_m);
        const int N = 360;
        // The drape-to-drape part of the noise is common to all depths of one
        // drape (the same folds are cut at every depth), so a stack of D depths
        // is one draw of it, not D independent ones: its floor is scaled by
        // sqrt(D), which keeps a deep stack from outvoting D and the node count.
        const double corr = std::sqrt(static_cast<double>(meas.contours.size()));
        add("mean_radius", s.mean_radius_m, m.mean_radius_m, noise.contour_sigma(corr * noise.radius_seed_m, N), m.depth_m);
        add("fold_rms", s.fold_rms_m, m.fold_rms_m, noise.contour_sigma(corr * noise.fold_seed_m, N / 2), m.depth_m);
        add("cos2", s.cos2_m, m.cos2_m, noise.contour_sigma(corr * noise.axis_seed_m, N / 2), m.depth_m, 2);
        add("cos4", s.cos4_m, m.cos4_m, noise.contour_sigma(corr * noise.axis_seed_m, N / 2), m.depth_m, 4);
        // The signed first harmonic: the contour's shift off the pedestal axis (a
        // profiler or specimen off the axis), linear in the shift where |c_1| is not.
        add("cos1", s.cos1_m, m.cos1_m, noise.contour_sigma(corr * noise.axis_seed_m, N / 2), m.depth_m, 1);
        add("sin1", s.sin1_m, m.sin1_m, noise.contour_sigma(corr * noise.axis_seed_m, N / 2), m.depth_m, 1);
        // |c_1| is left out: the signed a1, b1 above carry the first harmonic linearly.
        for (int k = 2; k <= noise.harmonics; ++k) {
            const double ms = k <= static_cast<int>(s.magnitudes_m.size()) ? s.magnitudes_m[k - 1] : 0.0;
            const double mm = k <= static_cast<int>(m.magnitudes_m.size()) ? m.magnitudes_m[k - 1] : 0.0;
            add("harmonic", ms, mm, noise.contour_sigma(corr * noise.fold_seed_m, N / 2), m.depth_m, k);
        }
    }
    return out;
}

DrapeFeatures average_features(const std::vector<DrapeFeatures>& f, std::vector<double>* closed_fraction)
{
    DrapeFeatures a;
    if (f.empty()) return a;
    const double n = static_cast<double>(f.size());
    a.drape_coefficient_percent = 0;
    a.node_count = 0;
    a.hem_min_z = 0;
    for (const auto& x : f) {
        a.drape_coefficient_percent += x.drape_coefficient_percent / n;
        a.node_count += x.node_count / n;
        a.hem_min_z += x.hem_min_z / n;
    }
    const std::size_t depths = f.front().contours.size();
    if (closed_fraction) closed_fraction->assign(depths, 0.0);
    for (std::size_t d = 0; d < depths; ++d) {
        int closed = 0;
        for (const auto& x : f) closed += x.contours[d].closed ? 1 : 0;
        if (closed_fraction) (*closed_fraction)[d] = closed / n;
        ContourFeatures c;
        c.depth_m = f.front().contours[d].depth_m;
        c.closed = closed > 0;
        int used = 0;
        for (const auto& x : f) {
            const ContourFeatures& s = x.contours[d];
            if (closed > 0 && !s.closed) continue;
            if (s.magnitudes_m.empty()) continue; // too few hits to fit
            ++used;
            c.mean_radius_m += s.mean_radius_m;
            c.fold_rms_m += s.fold_rms_m;
            c.cos2_m += s.cos2_m;
            c.cos4_m += s.cos4_m;
            c.cos1_m += s.cos1_m;
            c.sin1_m += s.sin1_m;
            c.node_count += s.node_count;
            if (c.magnitudes_m.size() < s.magnitudes_m.size()) c.magnitudes_m.resize(s.magnitudes_m.size(), 0.0);
            for (std::size_t k = 0; k < s.magnitudes_m.size(); ++k) c.magnitudes_m[k] += s.magnitudes_m[k];
            if (used == 1) c.series = s.series;
        }
        if (used > 0) {
            c.mean_radius_m /= used;
            c.fold_rms_m /= used;
            c.cos2_m /= used;
            c.cos4_m /= used;
            c.cos1_m /= used;
            c.sin1_m /= used;
            c.node_count /= used;
            for (double& m : c.magnitudes_m) m /= used;
        }
        a.contours.push_back(std::move(c));
    }
    return a;
}

double chi_square(const std::vector<ResidualTerm>& r)
{
    double s = 0;
    for (const auto& t : r)
        if (t.fitted) s += t.whitened() * t.whitened();
    return s;
}

std::string channel_of(const std::string& kind)
{
    if (kind == "dc" || kind == "nodes" || kind == "hem") return kind;
    if (kind.rfind("prior", 0) == 0) return "prior";
    return "contours";
}

std::vector<std::string> parse_channels(const std::string& list)
{
    std::vector<std::string> out;
    std::size_t pos = 0;
    while (pos <= list.size()) {
        const std::size_t c = list.find(',', pos);
        const std::string name = list.substr(pos, c == std::string::npos ? std::string::npos : c - pos);
        if (name != "dc" && name != "nodes" && name != "hem" && name != "contours")
            throw ParameterError("channels: '" + name + "' is not one of dc, nodes, hem, contours");
        out.push_back(name);
        if (c == std::string::npos) break;
        pos = c + 1;
    }
    if (out.empty()) throw ParameterError("channels: empty list");
    return out;
}

} // namespace drape::estimate
