// Record loading, features and the residual analysis: fast (one small drape, for the side view's hem).
#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/estimate/measured.hpp"
#include "engine/estimate/objective.hpp"
#include "engine/estimate/residual.hpp"

#include "synthetic.hpp"

#include <QTest>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>

using namespace drape;
using namespace drape::estimate;

namespace {
const std::string kSetA = std::string(DRAPE_SHARED_DIR) + "/data/drape-lab/set-a/";

/// A circle of radius r0 [m] with `nodes` sinusoidal folds of amplitude a [m], shifted by (dx, dy).
cloth::RadialProfile folded(double r0, int nodes, double a, double dx = 0, double dy = 0, int N = 360)
{
    cloth::Polygon2 poly;
    for (int k = 0; k < 2000; ++k) {
        const double t = 2 * std::numbers::pi * k / 2000;
        const double r = r0 + a * std::cos(nodes * t);
        poly.emplace_back(r * std::cos(t) + dx, r * std::sin(t) + dy);
    }
    return cloth::radial_profile(poly, N);
}
} // namespace

class TestRecords : public QObject {
    Q_OBJECT
private slots:
    void loadsLabRecordInSI()
    {
        const MeasuredDrape m = load_record(kSetA + "DL-A02");
        QCOMPARE(m.id, std::string("DL-A02"));
        QCOMPARE(m.sample_diameter, 0.300);
        QCOMPARE(m.disc_diameter, 0.150);
        QVERIFY(std::abs(m.areal_density - 0.120) < 1e-12); // 120 g/m^2
        QVERIFY(std::abs(m.thickness - 0.35e-3) < 1e-12);
        QCOMPARE(m.contours.size(), std::size_t(9));       // depths_mm 5..45 in meta.json
        QVERIFY(std::abs(m.contours.front().depth_m - 0.005) < 1e-12);
        for (const auto& c : m.contours) {
            QCOMPARE(c.profile.size(), 360);
            QVERIFY(c.profile.complete());
            // every cut lies outside the 75 mm disc and inside the 150 mm specimen radius
            for (double r : c.profile.r) QVERIFY(r > 0.075 - 1e-3 && r < 0.150);
        }
        QVERIFY(m.top_camera.has_value());
        // the pedestal axis at the pedestal top projects near the principal point of the top camera
        const Eigen::Vector2d c = m.top_camera->project({0, 0, 0});
        QVERIFY(std::abs(c.x() - m.top_camera->cx) < 2 && std::abs(c.y() - m.top_camera->cy) < 2);
    }

    /// The pedestal in the record's side photo: the declared 150 mm on DL-A02; with
    /// meta.json declaring 156 mm instead, the record says so in a note (the fit
    /// simulates what is declared).
    void pedestalIsCheckedInTheSidePhoto()
    {
        namespace fs = std::filesystem;
        const MeasuredDrape m = load_record(kSetA + "DL-A02");
        QVERIFY(std::abs(m.pedestal_measured_diameter - 0.150) < 1e-3 && m.pedestal_measured_sigma < 1e-3);
        for (const auto& n : m.notes) QVERIFY2(n.find("pedestal") == std::string::npos, n.c_str());
        const fs::path dir = fs::temp_directory_path() / "drape_est_pedestal";
        fs::remove_all(dir);
        fs::copy(kSetA + "DL-A02", dir, fs::copy_options::recursive);
        std::string meta = read_file((dir / "meta.json").string());
        const std::string key = "\"support_disc_diameter_D2_mm\": 150.0";
        const auto at = meta.find(key);
        QVERIFY(at != std::string::npos);
        meta.replace(at, key.size(), "\"support_disc_diameter_D2_mm\": 156.0");
        std::ofstream(dir / "meta.json", std::ios::trunc) << meta;
        const MeasuredDrape w = load_record(dir.string());
        QCOMPARE(w.disc_diameter, 0.156);
        QVERIFY(std::abs(w.pedestal_measured_diameter - 0.150) < 1e-3);
        bool noted = false;
        for (const auto& n : w.notes) noted |= n.find("side photo shows a pedestal") != std::string::npos && n.find("156") != std::string::npos;
        QVERIFY(noted);
        fs::remove_all(dir);
    }

    /// Most labs have a camera, not a laser profiler: a record whose contours.csv
    /// is emptied (its header only), empty or missing is read from its photos (the
    /// top view's nodes, the side view's lowest hem point) and the meta's D; with
    /// neither photos nor numbers it is refused, naming the file.
    void recordWithoutContoursIsReadFromItsPhotos()
    {
        namespace fs = std::filesystem;
        const fs::path dir = fs::temp_directory_path() / "drape_est_photos_only";
        fs::remove_all(dir);
        fs::copy(kSetA + "DL-A02", dir, fs::copy_options::recursive);
        for (const char* contents : std::initializer_list<const char*>{"depth_mm,theta_deg,x_mm,y_mm\n", "", nullptr}) {
            if (contents) std::ofstream(dir / "contours.csv", std::ios::trunc) << contents;
            else fs::remove(dir / "contours.csv");
            const MeasuredDrape m = load_record(dir.string());
            QVERIFY(m.contours.empty());
            QVERIFY(std::isfinite(m.drape_coefficient_percent));
            QVERIFY2(m.node_count >= 2, qPrintable(QString::fromStdString(m.node_source)));
            QCOMPARE(m.node_source, std::string("top photo (capture layer)"));
            QVERIFY(m.hem_from_side_view && std::isfinite(m.hem_min_z));
            bool noted = false;
            for (const auto& n : m.notes) noted |= n.find("no laser contours") != std::string::npos;
            QVERIFY(noted);
        }
        // No contours and no photos: the meta's D alone is still a measurement...
        for (const char* photo : {"top.jpg", "side.jpg", "iso.jpg"}) fs::remove(dir / photo);
        const MeasuredDrape d_only = load_record(dir.string());
        QVERIFY(d_only.contours.empty() && std::isfinite(d_only.drape_coefficient_percent) && d_only.node_count < 0);
        // ...without it there is nothing to fit.
        std::string meta = read_file((dir / "meta.json").string());
        const auto at = meta.find("\"lab_drape_coefficient_percent\"");
        QVERIFY(at != std::string::npos);
        meta.replace(at, std::string("\"lab_drape_coefficient_percent\"").size(), "\"lab_note\"");
        std::ofstream(dir / "meta.json", std::ios::trunc) << meta;
        try {
            load_record(dir.string());
            QFAIL("expected an error");
        } catch (const FileError& e) {
            QVERIFY2(std::string(e.what()).find("contours.csv: no laser contours") != std::string::npos, e.what());
        }
        fs::remove_all(dir);
    }

    void badFolderThrowsFileError()
    {
        QVERIFY_THROWS_EXCEPTION(FileError, load_record("/nonexistent/record"));
        const auto dir = std::filesystem::temp_directory_path() / "drape_est_bad_record";
        std::filesystem::create_directories(dir);
        std::ofstream(dir / "meta.json") << R"({"configuration": {"specimen_diameter_D1_mm": 300}})";
        try {
            load_record(dir.string());
            QFAIL("expected an error");
        } catch (const Error& e) {
            QVERIFY(std::string(e.what()).find("support_disc_diameter_D2_mm") != std::string::npos); // names the field
        }
        std::filesystem::remove_all(dir);
    }

    void featuresArePhaseFree()
    {
        // The same folds turned by an arbitrary angle give the same features
        // (except the axis-locked cos terms, which are zero for 7 folds).
        const auto a = contour_features(folded(0.09, 7, 0.006), 0.01);
        cloth::Polygon2 poly;
        for (int k = 0; k < 2000; ++k) {
            const double t = 2 * std::numbers::pi * k / 2000;
            const double r = 0.09 + 0.006 * std::cos(7 * (t - 0.37));
            poly.emplace_back(r * std::cos(t), r * std::sin(t));
        }
        const auto b = contour_features(cloth::radial_profile(poly, 360), 0.01);
        QCOMPARE(a.node_count, 7);
        QCOMPARE(b.node_count, 7);
        QVERIFY(std::abs(a.mean_radius_m - b.mean_radius_m) < 2e-5);
        QVERIFY(std::abs(a.magnitudes_m[6] - b.magnitudes_m[6]) < 2e-5);
        QVERIFY(std::abs(a.magnitudes_m[6] - 0.006) < 1e-4);
        QVERIFY(std::abs(a.fold_rms_m - 0.006 / std::sqrt(2.0)) < 1e-4);
    }

    void residualOnNoiseDoesNotCryWolf()
    {
        // Residual terms drawn from the noise itself: no discrepancy reported.
        std::mt19937 rng(3);
        std::normal_distribution<double> g(0, 1);
        std::vector<ResidualTerm> terms;
        for (int d = 1; d <= 6; ++d) {
            for (const char* kind : {"mean_radius", "fold_rms", "cos2", "cos4", "cos1", "sin1"}) {
                ResidualTerm t;
                t.kind = kind;
                t.harmonic = std::string(kind) == "cos1" || std::string(kind) == "sin1" ? 1 : 0;
                t.depth_m = 0.005 * d;
                t.sigma = 1e-3;
                t.measured = 0.1;
                t.simulated = 0.1 + 1e-3 * g(rng);
                terms.push_back(t);
            }
            for (int k = 2; k <= 8; ++k) { // k = 1: the signed a1, b1 above
                ResidualTerm t;
                t.kind = "harmonic";
                t.harmonic = k;
                t.depth_m = 0.005 * d;
                t.sigma = 1e-3;
                t.measured = 0.003;
                t.simulated = 0.003 + 1e-3 * g(rng);
                terms.push_back(t);
            }
        }
        const ResidualAnalysis a = analyse_residual(terms, 3);
        QVERIFY(!a.exceeds_noise);
        QVERIFY(a.candidate_effects.empty());
        QVERIFY(a.dominant_harmonics.empty());
    }

    void oppositeShiftsDoNotCancel()
    {
        // Two records whose stacks are shifted 2 sigma per depth in opposite
        // directions: pooled they would cancel; per record the shift is seen.
        std::vector<ResidualTerm> terms;
        for (int r = 0; r < 2; ++r)
            for (int d = 1; d <= 5; ++d)
                for (const char* kind : {"cos1", "sin1"}) {
                    ResidualTerm t;
                    t.record = r;
                    t.kind = kind;
                    t.harmonic = 1;
                    t.depth_m = 0.005 * d;
                    t.sigma = 1e-3;
                    t.measured = std::string(kind) == "cos1" ? (r == 0 ? 2e-3 : -2e-3) : 0.0;
                    t.simulated = 0.0;
                    terms.push_back(t);
                }
        const ResidualAnalysis a = analyse_residual(terms, 3);
        double z = 0;
        for (const auto& [k, v] : a.signature_z)
            if (k == "specimen_off_centre") z = v;
        QVERIFY2(z > 6, "each record's shift counts (2 sigma x sqrt(5) depths per record)");
        QVERIFY(std::find(a.candidate_effects.begin(), a.candidate_effects.end(), "specimen_off_centre") != a.candidate_effects.end());
    }

    void offCentreContoursPointToHarmonicOne()
    {
        // A measured drape shifted by 6 mm against a centred model: the
        // features differ in harmonic 1 and the analysis names the effect.
        const NoiseModel noise;
        DrapeFeatures meas, sim;
        meas.drape_coefficient_percent = sim.drape_coefficient_percent = 35;
        meas.node_count = sim.node_count = 7;
        for (int d = 1; d <= 6; ++d) {
            meas.contours.push_back(contour_features(folded(0.08 + 0.002 * d, 7, 0.001 * d, 0.006, 0.0), 0.005 * d));
            sim.contours.push_back(contour_features(folded(0.08 + 0.002 * d, 7, 0.001 * d), 0.005 * d));
        }
        const std::vector<double> closed(6, 1.0);
        const auto terms = residual_terms(0, meas, sim, closed, noise);
        const ResidualAnalysis a = analyse_residual(terms, 3);
        QVERIFY(a.exceeds_noise);
        QVERIFY(!a.dominant_harmonics.empty());
        QCOMPARE(a.dominant_harmonics.front(), 1);
        QVERIFY(std::find(a.candidate_effects.begin(), a.candidate_effects.end(), "specimen_off_centre") != a.candidate_effects.end());
        // and the centred pair is within the noise
        const auto same = residual_terms(0, sim, sim, closed, noise);
        QVERIFY(!analyse_residual(same, 3).exceeds_noise);
    }

    void untiltedStackRecoversItsAxisLine()
    {
        // Folded cuts whose axis moves by offset + depth x tilt (a tilted profiler):
        // the untilted stack finds the line and centres every cut (a1, b1 ~ 0);
        // re-centring finds only the mean shift and leaves the slope.
        const Eigen::Vector2d offset(0.5e-3, -0.3e-3), tilt(0.12, 0.3);
        std::vector<cloth::RadialProfile> stack, same;
        std::vector<double> depths;
        for (int d = 1; d <= 5; ++d) {
            const double depth = 0.005 * d;
            const Eigen::Vector2d c = offset + depth * tilt;
            stack.push_back(folded(0.08 + 0.002 * d, 6, 0.001 * d, c.x(), c.y()));
            depths.push_back(depth);
        }
        same = stack;
        Eigen::Vector2d found_tilt;
        const Eigen::Vector2d found = untilt_stack(stack, depths, found_tilt);
        QVERIFY2((found - offset).norm() < 1e-5, qPrintable(QString("%1 %2").arg(found.x()).arg(found.y())));
        QVERIFY2((found_tilt - tilt).norm() < 2e-3, qPrintable(QString("%1 %2").arg(found_tilt.x()).arg(found_tilt.y())));
        for (std::size_t i = 0; i < stack.size(); ++i) {
            const ContourFeatures f = contour_features(stack[i], depths[i]);
            QVERIFY2(std::hypot(f.cos1_m, f.sin1_m) < 2e-5, qPrintable(QString::number(std::hypot(f.cos1_m, f.sin1_m))));
        }
        recentre_stack(same);
        const ContourFeatures deepest = contour_features(same.back(), depths.back());
        QVERIFY(std::hypot(deepest.cos1_m, deepest.sin1_m) > 2e-3); // 10 mm x 0.32 from the mean depth
        // One cut: the mean shift, no tilt.
        std::vector<cloth::RadialProfile> one = {folded(0.08, 6, 0.002, 1e-3, 0)};
        QVERIFY((untilt_stack(one, {0.01}, found_tilt) - Eigen::Vector2d(1e-3, 0)).norm() < 1e-5);
        QCOMPARE(found_tilt, Eigen::Vector2d(0, 0));
    }

    void sideViewHemIsContinuousAtTheWindowEdges()
    {
        // A hem of 72 vertices whose lowest vertex sits just outside the side view's
        // window: 12 mm below every vertex inside it.
        const double pi = std::numbers::pi, step = 2 * pi / 72;
        std::vector<double> theta, z;
        for (int k = 0; k < 72; ++k) {
            theta.push_back(-pi + k * step);
            z.push_back(-0.060 + 0.004 * std::cos(5 * theta.back()));
        }
        const int deep = 30; // theta = -pi / 6
        z[deep] = -0.080;
        const double a = -pi + 5 * step, tv = theta[deep];
        double inside = 1;
        for (int k = 5; k < deep; ++k) inside = std::min(inside, z[static_cast<std::size_t>(k)]);
        QVERIFY(inside - z[deep] > 0.01);
        // Edges on vertices: the lowest vertex inside.
        QCOMPARE(hem_min_over_arc(theta, z, a, theta[deep - 1]), std::min(inside, z[deep - 1]));
        // The edge across the deep vertex: no jump (the rule that took a vertex whole
        // when it entered jumped by 12 mm here).
        const double before = hem_min_over_arc(theta, z, a, tv - 1e-9), after = hem_min_over_arc(theta, z, a, tv + 1e-9);
        QVERIFY2(std::abs(after - before) < 1e-6, qPrintable(QString::number(after - before)));
        // Lipschitz in the edge: never steeper than the hem's steepest segment.
        double steepest = 0;
        for (int k = 0; k < 72; ++k) steepest = std::max(steepest, std::abs(z[static_cast<std::size_t>((k + 1) % 72)] - z[static_cast<std::size_t>(k)]) / step);
        double prev = hem_min_over_arc(theta, z, a, tv - 2 * step);
        for (double b = tv - 2 * step + 1e-4; b < tv + 2 * step; b += 1e-4) {
            const double v = hem_min_over_arc(theta, z, a, b);
            QVERIFY(std::abs(v - prev) <= steepest * 1e-4 * 1.0001 + 1e-12);
            QVERIFY(v <= prev + 1e-15); // a wider window sees no higher minimum
            prev = v;
        }
        // Continuous in a vertex's position too: the deep vertex moved across the edge.
        auto moved = theta;
        const double b = tv - 0.5 * step;
        moved[deep] = b + 1e-9;
        const double out = hem_min_over_arc(moved, z, a, b);
        moved[deep] = b - 1e-9;
        QVERIFY(std::abs(hem_min_over_arc(moved, z, a, b) - out) < 1e-6);
        // A window at the seam of the angles (-pi) between two vertices: read between
        // the last vertex (pi - step / 2) and the first (-pi + step / 2), periodically.
        std::vector<double> half(theta);
        for (double& t : half) t += 0.5 * step;
        std::vector<double> zs(z);
        zs[0] = -0.070;
        zs[71] = -0.050;
        const double seam = hem_min_over_arc(half, zs, -pi, -pi + 0.25 * step);
        QVERIFY2(std::abs(seam - (-0.050 + 0.75 * (-0.070 + 0.050))) < 1e-12, qPrintable(QString::number(seam)));
        QVERIFY(std::isnan(hem_min_over_arc({}, {}, a, b)));
        QVERIFY(std::isnan(hem_min_over_arc(theta, z, b, a))); // an empty window
        QCOMPARE(hem_min_over_arc({0.1}, {-0.05}, -1.0, 0.0), -0.05); // one vertex: a constant curve
        // A vertex whose solve diverged is left out, not sorted (NaN has no order).
        std::vector<double> bad_theta(theta), bad_z(z);
        bad_theta[3] = NAN;
        bad_z[40] = NAN;
        QVERIFY(std::isfinite(hem_min_over_arc(bad_theta, bad_z, a, theta[deep - 1])));
    }
    void sideViewHemOfADrapeTurnsSmoothly()
    {
        // A drape turned about the pedestal axis by a fraction of its hem's vertex
        // spacing: hem vertices cross the side view's window edges, and the hem the
        // fit compares moves no faster than the hem's steepest slope allows (the rule
        // that took a vertex whole when it entered jumped by the height between a
        // trough and its neighbour: the Jacobian's 1e-3-decade differences read that
        // as metres per decade on DL-A09).
        cloth::FabricParams p;
        p[cloth::Param::BendWarp] = 2e-5;
        p[cloth::Param::BendWeft] = 8e-6;
        p[cloth::Param::Shear] = 20;
        p[cloth::Param::AreaDensity] = 0.2;
        const cloth::DrapeSetup setup = test::drape_setup(0.30, 0.15, 17, 3);
        const cloth::DrapeResult d = cloth::simulate_drape(p, setup);
        MeasuredDrape like = synthesize_record(d, setup, p, 0.3e-3, setup.seed + 100, "turned");
        like.hem_from_side_view = true;
        like.contours.clear(); // the hem alone
        const double pi = std::numbers::pi;
        const std::size_t n = d.hem.theta.size();
        QVERIFY(n > 20);
        double steepest = 0; // |dz/dtheta| between neighbours in angle
        std::vector<std::size_t> idx(n);
        for (std::size_t i = 0; i < n; ++i) idx[i] = i;
        std::sort(idx.begin(), idx.end(), [&](std::size_t i, std::size_t j) { return d.hem.theta[i] < d.hem.theta[j]; });
        for (std::size_t k = 0; k < n; ++k) { // and the segment across the seam at -pi
            const std::size_t k1 = (k + 1) % n;
            const double dt = d.hem.theta[idx[k1]] - d.hem.theta[idx[k]] + (k1 == 0 ? 2 * pi : 0.0);
            if (dt > 1e-9) steepest = std::max(steepest, std::abs(d.hem.z[idx[k1]] - d.hem.z[idx[k]]) / dt);
        }
        // A third of a turn in steps of a twentieth of the vertex spacing: troughs
        // pass both edges of the window.
        const double dalpha = 2 * pi / static_cast<double>(n) / 20;
        const int steps = static_cast<int>(2 * pi / 3 / dalpha);
        double prev = NAN, worst = 0, lo = HUGE_VAL, hi = -HUGE_VAL;
        for (int k = 0; k <= steps; ++k) {
            cloth::DrapeResult t = d;
            for (double& a : t.hem.theta) a = std::remainder(a + k * dalpha, 2 * pi);
            const double h = drape_features(t, like).hem_min_z;
            QVERIFY(std::isfinite(h));
            if (k > 0) worst = std::max(worst, std::abs(h - prev));
            prev = h;
            lo = std::min(lo, h);
            hi = std::max(hi, h);
        }
        qInfo("side-view hem %.4f..%.4f m over the turn; largest step %.3g m for a turn of %.3g rad (steepest hem slope %.3g m/rad)", lo, hi, worst,
              dalpha, steepest);
        QVERIFY2(hi - lo > 1e-3, "the turn moves the side view's hem (troughs pass the window's edges)");
        QVERIFY(worst <= steepest * dalpha * 1.01 + 1e-12);
    }
    void modelVariants()
    {
        QCOMPARE(fit_variables(ModelVariant::Baseline).size(), std::size_t(3));
        QCOMPARE(fit_variables(ModelVariant::Baseline, true).size(), std::size_t(2)); // warp and weft bending tied
        QCOMPARE(fit_variables(ModelVariant::Baseline, true).front().params.size(), std::size_t(2));
        QCOMPARE(fit_variables(ModelVariant::Stiffening).size(), std::size_t(4));
        QCOMPARE(fit_variables(ModelVariant::Stiffening).back().name, std::string("bend_stiffening_radius_m"));
        QVERIFY(!fit_variables(ModelVariant::Stiffening).back().log_scale); // 0 = linear bending stays reachable
        QVERIFY(fit_variables(ModelVariant::Full).size() > 4);
        QCOMPARE(to_string(parse_model_variant("stiffening")), std::string("stiffening"));
        QCOMPARE(fit_variables(ModelVariant::Softening).back().name, std::string("bend_softening_radius_m"));
        QCOMPARE(to_string(parse_model_variant("softening")), std::string("softening"));
        QCOMPARE(fit_variables(ModelVariant::Buckling).back().name, std::string("buckling_length_m"));
        QVERIFY(!fit_variables(ModelVariant::Buckling).back().log_scale); // 0 = the linear membrane stays reachable
        QCOMPARE(to_string(parse_model_variant("buckling")), std::string("buckling"));
        for (const auto& v : fit_variables(ModelVariant::Full))
            for (auto p : v.params) QVERIFY(cloth::spec(p).affects_statics); // never fit a damper
        QVERIFY_THROWS_EXCEPTION(ParameterError, parse_model_variant("nonsense"));
    }
};

QTEST_APPLESS_MAIN(TestRecords)
#include "tst_records.moc"
