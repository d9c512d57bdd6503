#include "engine/estimate/effects.hpp"

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drape::estimate {

using cloth::Param;

const std::vector<EffectSpec>& effect_library()
{
    static const std::vector<EffectSpec> lib = [] {
        std::vector<EffectSpec> l;
        auto param = [&](std::string name, std::string family, std::string doc, std::vector<Param> ps) {
            EffectSpec e;
            e.name = std::move(name);
            e.family = std::move(family);
            e.description = std::move(doc);
            e.kind = EffectKind::Parameter;
            e.params = std::move(ps);
            e.amplitude_unit = "relative change";
            l.push_back(std::move(e));
        };
        auto ratio = [&](std::string name, std::string family, std::string doc, Param up, Param down) {
            param(std::move(name), std::move(family), std::move(doc), {up, down});
            l.back().weights = {1.0, -1.0};
            l.back().amplitude_unit = "relative change of each (the ratio by twice that)";
        };
        auto sw = [&](std::string name, std::string family, std::string doc, std::vector<Param> ps, double on, bool grip, bool vertex) {
            EffectSpec e;
            e.name = std::move(name);
            e.family = std::move(family);
            e.description = std::move(doc);
            e.kind = EffectKind::Switch;
            e.params = std::move(ps);
            e.on_value = on;
            e.disc_grip = grip;
            e.vertex_contact = vertex;
            e.amplitude_unit = "fraction of the switched-on effect";
            l.push_back(std::move(e));
        };
        auto meas = [&](std::string name, std::string doc, EffectKind k, std::string unit) {
            EffectSpec e;
            e.name = std::move(name);
            e.family = "measurement";
            e.description = std::move(doc);
            e.kind = k;
            e.amplitude_unit = std::move(unit);
            l.push_back(std::move(e));
        };
        meas("profiler_off_axis", "the laser profiler (or the specimen) off the pedestal axis: contours shifted sideways (2 parameters, x and y)",
             EffectKind::ProfilerAxis, "m (x, y shift)");
        meas("profiler_tilt",
             "the profiler's axis tilted against the pedestal's, or the rig off level (a skirt hangs plumb): contours shifted sideways in "
             "proportion to their depth (2 parameters, x and y); a drape that leans (specimen_weight_gradient) looks alike on contours",
             EffectKind::ProfilerTilt, "rad (x, y tilt)");
        meas("camera_scale", "the photos' scale off (calibration): the drape coefficient and the hem height scaled", EffectKind::CameraScale,
             "fraction");
        meas("profiler_scale", "the laser contours' scale off: every contour radius scaled", EffectKind::ProfilerScale, "fraction");
        meas("profiler_depth",
             "the laser profiler's height datum off: every cut taken deeper (positive) than its declared depth below the pedestal top - "
             "slices wider than the model's at every depth while the photos' D and hem are not (the rim signature's contour half)",
             EffectKind::ProfilerDepth, "m (deeper)");
        {
            EffectSpec e;
            e.name = "specimen_weight_gradient";
            e.family = "specimen";
            e.description = "the specimen heavier on one side (areal density changing linearly across it; x and y): the skirt leans away "
                            "from the heavy side, more so the deeper";
            e.kind = EffectKind::Specimen;
            e.density_gradient = 0.3;
            e.amplitude_unit = "fraction per radius (x, y)";
            l.push_back(std::move(e));
        }
        param("buckling", "membrane", "the membrane's compression limit (buckling_length_m): how easily the fabric buckles in its plane",
              {Param::BucklingLength});
        param("tensile_stiffness", "membrane", "the tensile stiffness warp and weft together (stretch_warp_N_m, stretch_weft_N_m)",
              {Param::StretchWarp, Param::StretchWeft});
        ratio("tensile_anisotropy", "membrane", "the tensile stiffness warp against weft (stretch_warp_N_m up, stretch_weft_N_m down)",
              Param::StretchWarp, Param::StretchWeft);
        param("shear_stiffness", "membrane", "the in-plane shear stiffness (shear_N_m)", {Param::Shear});
        sw("bending_stiffening", "bending", "bending that stiffens at small radii (bend_stiffening_radius_m switched on at 5 mm)",
           {Param::BendStiffeningRadius}, 5e-3, false, false);
        sw("bending_softening", "bending", "bending that yields at small radii (bend_softening_radius_m switched on at 5 mm)",
           {Param::BendSofteningRadius}, 5e-3, false, false);
        ratio("bending_anisotropy", "bending", "the bending stiffness warp against weft (bend_warp_Nm up, bend_weft_Nm down) when the fit ties them",
              Param::BendWarp, Param::BendWeft);
        param("declared_weight", "declared", "the declared areal density wrong (areal_density_kg_m2)", {Param::AreaDensity});
        param("declared_thickness", "declared", "the declared thickness wrong (thickness_m: the contact offset)", {Param::Thickness});
        sw("disc_grip", "contact", "the specimen gripped by the pedestal top (static friction) instead of sliding", {}, 0, true, false);
        sw("self_contact", "contact", "the folds touching each other (self-contact switched on at the declared thickness)", {}, 0, false, false);
        l.back().self_contact = true;
        sw("contact_resolution", "numerical", "the pedestal contact resolved at mesh vertices only (a coarse mesh cutting the rim)", {}, 0,
           false, true);
        return l;
    }();
    return lib;
}

double effect_weight(const EffectSpec& spec, std::size_t i)
{
    return i < spec.weights.size() ? spec.weights[i] : 1.0;
}

std::string fitted_by(const EffectSpec& sp, const std::vector<FitVariable>& vars)
{
    if (sp.params.empty()) return {};
    // The parameters in play: the effect's and every fitted variable's that
    // shares one with it (a variable that moves others too covers less).
    std::vector<Param> ps = sp.params;
    auto index = [&](Param q) {
        for (std::size_t i = 0; i < ps.size(); ++i)
            if (ps[i] == q) return static_cast<Eigen::Index>(i);
        ps.push_back(q);
        return static_cast<Eigen::Index>(ps.size() - 1);
    };
    // The variables that touch a parameter in play, and theirs in turn (a
    // variable tying warp to weft brings in one fitting weft alone).
    std::vector<const FitVariable*> touching;
    std::vector<char> taken(vars.size(), 0);
    for (bool grew = true; grew;) {
        grew = false;
        for (std::size_t j = 0; j < vars.size(); ++j) {
            if (taken[j]) continue;
            bool touches = false;
            for (Param q : vars[j].params)
                touches = touches || std::find(ps.begin(), ps.end(), q) != ps.end();
            if (!touches) continue;
            taken[j] = 1;
            grew = true;
            touching.push_back(&vars[j]);
            for (Param q : vars[j].params) index(q);
        }
    }
    if (touching.empty()) return {};
    std::string keys;
    for (Param e : sp.params)
        for (const FitVariable* v : touching)
            if (std::find(v->params.begin(), v->params.end(), e) != v->params.end()) {
                keys += (keys.empty() ? "" : ", ") + std::string(cloth::spec(e).key);
                break;
            }
    const auto n = static_cast<Eigen::Index>(ps.size());
    Eigen::VectorXd w = Eigen::VectorXd::Zero(n);
    for (std::size_t i = 0; i < sp.params.size(); ++i) w[index(sp.params[i])] = effect_weight(sp, i);
    Eigen::MatrixXd V = Eigen::MatrixXd::Zero(n, static_cast<Eigen::Index>(touching.size()));
    for (std::size_t j = 0; j < touching.size(); ++j)
        for (Param q : touching[j]->params) V(index(q), static_cast<Eigen::Index>(j)) = 1;
    const Eigen::VectorXd left = w - V * V.colPivHouseholderQr().solve(w);
    return left.norm() < 1e-9 * w.norm() ? keys : std::string();
}

namespace {

/// c.channels and c.explains_reached from the joint refit's residual `after`
/// against the fit's `r`, channel by channel (`channel[row]`: 0 photos, 1
/// contours, -1 neither); a channel's reach is its share of the weight of the
/// signature's columns `S` (unprojected).
void explain_channels(EffectCandidate& c, const Eigen::VectorXd& r, const Eigen::VectorXd& after, const Eigen::MatrixXd& S,
                      const std::vector<int>& channel, double s2)
{
    const double weight = S.squaredNorm();
    static const char* names[] = {"photos", "contours"};
    for (int ch : {0, 1}) {
        EffectCandidate::Channel out{names[ch], 0.0, 0.0};
        double w = 0, before = 0, left = 0;
        for (Eigen::Index i = 0; i < r.size(); ++i)
            if (channel[static_cast<std::size_t>(i)] == ch) {
                w += S.row(i).squaredNorm();
                before += r[i] * r[i];
                left += after[i] * after[i];
            }
        out.reach = weight > 0 ? w / weight : 0.0;
        out.delta_chi2 = (before - left) / s2;
        if (out.reach >= kChannelReach && out.delta_chi2 < -kChannelSlack) c.explains_reached = false;
        c.channels.push_back(out);
    }
    if (!c.explains_reached && c.verdict == "beyond noise") {
        std::string worse;
        for (const auto& ch : c.channels)
            if (ch.reach >= kChannelReach && ch.delta_chi2 < -kChannelSlack) {
                char buf[160];
                std::snprintf(buf, sizeof buf, "%s%s %+.1f", worse.empty() ? "" : ", ", ch.name.c_str(), ch.delta_chi2);
                worse += buf;
            }
        const std::string n = "its refit makes a channel it reaches worse (delta chi2 " + worse + "): not named";
        c.note = c.note.empty() ? n : c.note + "; " + n;
    }
}

} // namespace

std::vector<EffectCandidate> test_candidates(const Eigen::MatrixXd& J, const Eigen::VectorXd& r,
                                             const std::vector<EffectSignature>& signatures, int terms, double chi2_scale,
                                             const std::vector<int>& channel)
{
    const double s2 = std::isfinite(chi2_scale) ? std::max(1.0, chi2_scale) : 1.0;
    std::vector<EffectCandidate> out;
    // Projector onto the complement of the fitted columns (the fit has already
    // used what they can explain). Q of a rank-revealing QR spans J's range.
    Eigen::MatrixXd Q;
    if (J.cols() > 0) {
        Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(J);
        const auto rank = qr.rank();
        Q = Eigen::MatrixXd(qr.householderQ()).leftCols(rank);
    }
    auto project = [&](const Eigen::MatrixXd& S) -> Eigen::MatrixXd { return Q.size() ? Eigen::MatrixXd(S - Q * (Q.transpose() * S)) : S; };
    const Eigen::VectorXd rp = project(r);
    const double lnN = std::log(std::max(2, terms));
    for (const auto& sig : signatures) {
        EffectCandidate c;
        c.name = sig.spec->name;
        c.family = sig.spec->family;
        c.description = sig.spec->description;
        c.amplitude_unit = sig.spec->amplitude_unit;
        c.parameters = static_cast<int>(sig.columns.cols());
        if (!sig.available || sig.columns.cols() == 0 || !sig.columns.allFinite()) {
            c.verdict = "not testable";
            c.note = sig.why_not.empty() ? "no signature" : sig.why_not;
            out.push_back(std::move(c));
            continue;
        }
        const Eigen::MatrixXd S = project(sig.columns);
        // Columns the fitted parameters can already mimic carry nothing new.
        const double full = sig.columns.norm(), left = S.norm();
        if (!(full > 1e-9)) {
            c.verdict = "not testable";
            c.note = "it changes none of the fitted terms here (at this rest state)";
            out.push_back(std::move(c));
            continue;
        }
        // Less than 5 % new: what is left is rounding and the fit's own noise.
        if (!(left > 0.05 * std::max(full, 1e-300)) || !(left > 1e-9)) {
            c.verdict = "not testable";
            c.note = "its signature is what the fitted parameters already do (degenerate with them)";
            out.push_back(std::move(c));
            continue;
        }
        const Eigen::MatrixXd StS = S.transpose() * S;
        const Eigen::VectorXd Str = S.transpose() * rp;
        const Eigen::VectorXd a = StS.ldlt().solve(-Str); // amplitude that best removes the residual
        c.delta_chi2 = std::max(0.0, -Str.dot(a)) / s2;
        c.z = c.parameters == 1 ? -Str[0] / std::sqrt(StS(0, 0) * s2) : std::sqrt(c.delta_chi2);
        c.amplitude = a[0];
        c.amplitudes.assign(a.data(), a.data() + a.size());
        c.information = c.delta_chi2 - c.parameters * lnN;
        const double quantile = c.parameters == 1 ? 9.0 : 11.83; // 3 sigma (p = 0.0027) of chi2 with k dof
        c.verdict = c.delta_chi2 > quantile && c.information > 0 ? "beyond noise" : "within noise";
        // A first-order amplitude far outside the linear range (a parameter by more
        // than a factor 10, a switched effect - the specimen's too - more than 3
        // times over) is not a refit the engine would make: the effect would have
        // to be another one. The instruments' signatures are exact geometry - but
        // a depth datum's is the first order of r(z), curved near the rim: beyond
        // 10 mm (two of the lab's 5 mm steps between cuts; a shallow cut would be
        // above the pedestal top) it is not this effect either.
        const auto& sp = *sig.spec;
        const double limit = sp.kind == EffectKind::Parameter ? std::log(10.0)
                             : sp.kind == EffectKind::Switch  ? 3.0
                             : sp.kind == EffectKind::Specimen ? 3.0 * std::abs(sp.density_gradient)
                             : sp.kind == EffectKind::ProfilerDepth ? 0.010
                                                               : HUGE_VAL;
        if (a.norm() > limit) {
            if (c.verdict == "beyond noise") c.verdict = "within noise";
            c.note = "the refit would need an amplitude of " + std::to_string(c.parameters == 1 ? a[0] : a.norm()) + " " + c.amplitude_unit +
                     ", beyond the linear range: not this effect";
        }
        if (left < 0.3 * full && c.note.empty())
            c.note = "mostly degenerate with the fitted parameters (" + std::to_string(static_cast<int>(std::lround(100 * left / full))) +
                     " % of its signature is new)";
        // The joint refit's residual (the fitted columns and the effect's) is rp + S a:
        // the fitted columns' projection, then the effect's on what they leave.
        if (static_cast<Eigen::Index>(channel.size()) == r.size()) explain_channels(c, r, rp + S * a, sig.columns, channel, s2);
        out.push_back(std::move(c));
    }
    return out;
}

std::string name_effect(const std::vector<EffectCandidate>& c, double chi2, int dof)
{
    const EffectCandidate* best = nullptr;
    for (const auto& e : c)
        if (e.verdict == "beyond noise" && (!best || e.delta_chi2 > best->delta_chi2)) best = &e;
    if (!best) return {};
    for (const auto& e : c)
        if (&e != best && e.verdict == "beyond noise" && e.delta_chi2 + 2.0 * (best->parameters - e.parameters) > best->delta_chi2 - 2.0)
            return {}; // two explain it alike: a Bayes factor below e (2 ln B < 2, Kass & Raftery's "not worth more than a bare mention")
    if (std::isfinite(best->verified_delta_chi2) && best->verified_delta_chi2 < 0.5 * best->delta_chi2) return {}; // not borne out by a drape
    if (!best->explains_reached) return {}; // it trades one channel against another
    const double d = std::max(1, dof);
    const double bound = d + 3 * std::sqrt(2 * d);
    const double after = chi2 - best->delta_chi2;
    const bool explains = after < bound || best->delta_chi2 >= 0.5 * std::max(0.0, chi2 - d);
    return explains ? best->name : std::string();
}

} // namespace drape::estimate
