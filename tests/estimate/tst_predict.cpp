// Predictions of a preset on a set-up (unit): the fit's grid scaled with the
// specimen, the covariance rebuilt from a preset's fit section, and the interval
// of D made of its three terms around the mean of the drapes from flat.
#include "engine/core/error.hpp"
#include "engine/estimate/predict.hpp"

#include <QTest>

#include <cmath>

using namespace drape;
using namespace drape::estimate;
using cloth::Param;

namespace {
/// A fitted preset as drape fit writes it: provenance.grid, the first record's
/// diameter, two fitted coordinates with their sigmas and correlation.
fabric::FabricPreset fitted_preset(double sigma_warp, double sigma_weft, double rho)
{
    fabric::FabricPreset p;
    p.name = "fitted";
    p.params[Param::AreaDensity] = 0.2;
    p.params[Param::BendWarp] = 1.2e-5;
    p.params[Param::BendWeft] = 0.8e-5;
    fabric::Provenance prov;
    prov.tool = "drape fit";
    prov.grid = 17;
    prov.laying_load = 1.0;
    p.provenance = prov;
    fabric::FitSummary fit;
    fit.sample_diameter_m = 0.30;
    fit.disc_diameter_m = 0.15;
    fit.details["parameters"] = nlohmann::json::array(
        {{{"key", "bend_warp_Nm"}, {"role", "fitted"}, {"sigma_search_coordinate", sigma_warp}},
         {{"key", "bend_weft_Nm"}, {"role", "fitted"}, {"sigma_search_coordinate", sigma_weft}},
         {{"key", "shear_N_m"}, {"role", "held"}}});
    fit.details["records"] = nlohmann::json::array({{{"id", "A-300-150"}, {"sample_diameter_m", 0.30}, {"disc_diameter_m", 0.15},
                                                     {"measured_drape_coefficient_percent", 40.0}}});
    fit.details["correlation"] = {{"bend_warp_Nm", {{"bend_warp_Nm", 1.0}, {"bend_weft_Nm", rho}, {"shear_N_m", nullptr}}},
                                  {"bend_weft_Nm", {{"bend_warp_Nm", rho}, {"bend_weft_Nm", 1.0}, {"shear_N_m", nullptr}}},
                                  {"shear_N_m", {{"bend_warp_Nm", nullptr}, {"bend_weft_Nm", nullptr}, {"shear_N_m", 1.0}}}};
    p.fit = fit;
    return p;
}
} // namespace

class TestPredict : public QObject {
    Q_OBJECT
private slots:
    void gridScalesWithTheSpecimen()
    {
        const auto p = fitted_preset(0.1, 0.1, 0.0);
        QCOMPARE(*fit_grid_for(p, 0.30), 17);
        QCOMPARE(*fit_grid_for(p, 0.36), 21); // 20.4 -> 20 -> odd
        QCOMPARE(*fit_grid_for(p, 0.24), 15); // 13.6 -> 14 -> odd
        fabric::FabricPreset bare;
        QVERIFY(!fit_grid_for(bare, 0.30));
        cloth::DrapeSetup s;
        s.grid = 0;
        QCOMPARE(prediction_setup(bare, s).grid, 31);
        s.sample_diameter = 0.36;
        QCOMPARE(prediction_setup(p, s).grid, 21);
    }

    void covarianceComesBackFromThePreset()
    {
        std::vector<std::string> keys;
        const Eigen::MatrixXd C = fit_covariance(fitted_preset(0.1, 0.2, -0.5), keys);
        QCOMPARE(keys.size(), std::size_t(2)); // the held shear is not a fitted coordinate
        QCOMPARE(keys[0], std::string("bend_warp_Nm"));
        QVERIFY(std::abs(C(0, 0) - 0.01) < 1e-12);
        QVERIFY(std::abs(C(1, 1) - 0.04) < 1e-12);
        QVERIFY(std::abs(C(0, 1) + 0.5 * 0.1 * 0.2) < 1e-12);
        fabric::FabricPreset bare;
        QCOMPARE(fit_covariance(bare, keys).size(), Eigen::Index(0));
        QVERIFY(keys.empty());
    }

    void intervalHoldsTheDrapesAndItsTerms()
    {
        const auto p = fitted_preset(0.05, 0.05, 0.3);
        cloth::DrapeSetup s;
        s.sample_diameter = 0.30;
        s.disc_diameter = 0.15;
        s.grid = 0;
        PredictOptions o;
        o.seeds = 2;
        const Prediction r = predict_drape(p, prediction_setup(p, s), o);
        QCOMPARE(r.drapes.size(), std::size_t(2));
        QVERIFY(r.converged);
        QCOMPARE(r.setup.grid, 17);
        const double mean = 0.5 * (r.drapes[0].metrics.drape_coefficient_percent + r.drapes[1].metrics.drape_coefficient_percent);
        QVERIFY(std::abs(r.dc_percent - mean) < 1e-12);
        QVERIFY(r.parameters_known);
        QVERIFY(r.sigma_parameters_percent > 0);
        // Both bendings stiffen the drape: D rises along each coordinate.
        QCOMPARE(r.d_dc_per_coordinate.size(), std::size_t(2));
        QVERIFY(r.d_dc_per_coordinate[0] > 0 && r.d_dc_per_coordinate[1] > 0);
        QCOMPARE(r.sigma_repeat_percent, kRepeatSigmaPercent);
        const double sigma = std::sqrt(r.sigma_parameters_percent * r.sigma_parameters_percent +
                                       r.sigma_starts_percent * r.sigma_starts_percent + r.sigma_repeat_percent * r.sigma_repeat_percent);
        QVERIFY(std::abs(r.dc_upper95 - std::min(100.0, r.dc_percent + 1.96 * sigma)) < 1e-9);
        QVERIFY(r.dc_lower95 < r.dc_percent && r.dc_percent < r.dc_upper95);
        QVERIFY(r.nodes_lower <= r.node_min && r.node_max <= r.nodes_upper);
        QCOMPARE(r.nodes_upper - r.node_max, kRepeatFolds);
        // A wider covariance widens the parameter term (linearly in sigma).
        const Prediction wide = predict_drape(fitted_preset(0.10, 0.10, 0.3), prediction_setup(p, s), o);
        QVERIFY(std::abs(wide.sigma_parameters_percent / r.sigma_parameters_percent - 2.0) < 1e-6);
        // On its own set-up no transfer term; on another, a fraction of the change of
        // D from the nearest fitted record.
        QVERIFY(r.fitted_setup);
        QCOMPARE(r.transfer_from, std::string("A-300-150"));
        QCOMPARE(r.sigma_transfer_percent, 0.0);
        cloth::DrapeSetup other = s;
        other.sample_diameter = 0.36;
        other.disc_diameter = 0.18;
        const Prediction t = predict_drape(p, prediction_setup(p, other), o);
        QVERIFY(!t.fitted_setup);
        QVERIFY(std::abs(t.transfer_change_percent - (t.dc_percent - 40.0)) < 1e-9);
        QVERIFY(std::abs(t.sigma_transfer_percent - kTransferFraction * std::abs(t.transfer_change_percent)) < 1e-9);
        // Without intervals: the drapes only.
        o.intervals = false;
        o.seeds = 1;
        const Prediction bare = predict_drape(p, prediction_setup(p, s), o);
        QVERIFY(std::isnan(bare.dc_lower95));
        QCOMPARE(bare.sigma_starts_percent, 0.0);
        o.seeds = 0;
        QVERIFY_THROWS_EXCEPTION(ParameterError, predict_drape(p, prediction_setup(p, s), o));
    }
};

QTEST_APPLESS_MAIN(TestPredict)
#include "tst_predict.moc"
