// The ten set-a lab records: drape coefficient against the lab's drapemeter,
// node counts against a person's count on the overlays, contour fits.
#include "engine/capture/measure.hpp"
#include "engine/capture/report.hpp"

#include <QTest>

#include <filesystem>
#include <map>

namespace fs = std::filesystem;
using namespace drape;

namespace {
const fs::path kSetA = fs::path(DRAPE_SHARED_DIR) / "data/drape-lab/set-a";

// Counted by eye on the overlays (docs/capture/ and `drape measure --overlay`):
// fold crests on the traced outline, each with a visible trough either side.
const std::map<std::string, int> kNodesByEye = {
    {"DL-A01", 6}, {"DL-A02", 8}, {"DL-A03", 8}, {"DL-A04", 8}, {"DL-A05", 5},
    {"DL-A06", 7}, {"DL-A07", 6}, {"DL-A08", 6}, {"DL-A09", 5}, {"DL-A10", 6},
};
} // namespace

class TestCaptureSetA : public QObject {
    Q_OBJECT
private slots:
    void record_data()
    {
        QTest::addColumn<QString>("id");
        if (!fs::exists(kSetA)) return;
        for (const auto& [id, n] : kNodesByEye) {
            (void)n;
            QTest::newRow(id.c_str()) << QString::fromStdString(id);
        }
    }
    void record()
    {
        if (!fs::exists(kSetA)) QSKIP("shared/data/drape-lab/set-a not present");
        QFETCH(QString, id);
        const auto rec = record::read_record(kSetA / id.toStdString());
        QVERIFY(rec.lab_drape_coefficient_percent.has_value());
        const auto m = capture::measure_record(rec);
        QVERIFY(m.top.measured);
        const double d = m.top.metrics.drape_coefficient_percent, lab = *rec.lab_drape_coefficient_percent;
        qInfo("%s: D %.1f %% (lab %.1f, uncorrected %.1f), nodes %d, hem %.1f mm, side rms %.1f mm", qPrintable(id), d,
              lab, m.top.dc_plane_percent, m.top.metrics.node_count, *m.hem_min_height * 1e3,
              m.side.model_rms_diff * 1e3);
        QVERIFY2(std::abs(d - lab) <= 1.5, qPrintable(QString("D %1 vs lab %2").arg(d).arg(lab)));
        QCOMPARE(m.top.metrics.node_count, kNodesByEye.at(id.toStdString()));

        // Top camera checked against the four floor boards.
        QVERIFY(m.top_calibration && m.top_calibration->ok);
        QCOMPARE(static_cast<int>(m.top_calibration->boards_found.size()), 4);
        QVERIFY(m.top_calibration->rms_px_measured < 0.5);

        // Side view: hem found in front of the pedestal, below the pedestal top,
        // and consistent with the top view's height model.
        QVERIFY(m.side.measured);
        QVERIFY(m.side.hem_min_z < -0.02 && m.side.hem_min_z > -rec.pedestal_height);
        QVERIFY(m.side.model_rms_diff < 0.010);
        // The pedestal in the side photo is the declared one (150 mm on every set-a record).
        QVERIFY(m.side.pedestal.measured && !m.side.pedestal.differs);
        QVERIFY(std::abs(m.side.pedestal.diameter - 2 * rec.R2) < 1e-3);
        QVERIFY(m.hem_min_height && *m.hem_min_height <= m.side.hem_min_z);

        // Contours: every listed depth is fitted; the series reproduces the
        // points within the profiler noise, except where the contour itself
        // jumps between neighbouring rays (an overhanging fold: a Fourier series
        // cannot follow a step), which must then be flagged.
        QCOMPARE(m.contours.size(), rec.contour_depths.size());
        for (const auto& c : m.contours) {
            QVERIFY(c.harmonics >= 1);
            QVERIFY(std::abs(c.mean_radius) > rec.R2 && c.mean_radius < rec.R1);
            if (c.residual_rms > 1.1 * c.noise_sigma) {
                QVERIFY2(c.max_jump > 30 * c.noise_sigma,
                         qPrintable(QString("depth %1 mm residual %2 mm").arg(c.depth * 1e3).arg(c.residual_rms * 1e3)));
                bool flagged = false;
                for (const auto& w : m.warnings) flagged |= w.find("jumps") != std::string::npos;
                QVERIFY(flagged);
            }
        }
    }
};

QTEST_APPLESS_MAIN(TestCaptureSetA)
#include "tst_capture_seta.moc"
