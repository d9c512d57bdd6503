// Single top photos (no calibrated rig), through `drape measure` as a user runs
// it and through the library: scale from the disc rim, markers, a chessboard
// or px/mm; the perspective models side by side; segmentation under shadows,
// low contrast, white and dark cloth, prints, a reverse side, sequins, an
// upper disc; manual overrides; refusals; batch. Synthetic photos with known
// outlines (synthetic_photo.hpp, photo_scenes.hpp).
#include "engine/capture/exif.hpp"
#include "engine/capture/measure.hpp"
#include "engine/capture/report.hpp"
#include "engine/core/error.hpp"
#include "photo_scenes.hpp"
#include "synthetic.hpp"
#include "tests/slow_cases.hpp"

#include <QProcess>
#include <QTest>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace fs = std::filesystem;
using namespace drape;
using nlohmann::json;

namespace {

fs::path temp_dir(const std::string& name)
{
    const fs::path d = fs::temp_directory_path() / ("drape_tst_photo_" + std::to_string(::getpid())) / name;
    fs::remove_all(d);
    fs::create_directories(d);
    return d;
}

struct Run {
    int code = -1;
    std::string out, err;
};

Run run_drape(const std::vector<std::string>& args)
{
    QProcess p;
    QStringList a;
    for (const auto& s : args) a << QString::fromStdString(s);
    p.start(QCoreApplication::applicationDirPath() + "/../bin/drape", a);
    Run r;
    if (!p.waitForFinished(300000)) {
        p.kill();
        return r;
    }
    r.code = p.exitStatus() == QProcess::NormalExit ? p.exitCode() : -2;
    r.out = p.readAllStandardOutput().toStdString();
    r.err = p.readAllStandardError().toStdString();
    return r;
}

const synth_photo::Case& find_case(const std::string& name)
{
    static const auto all = synth_photo::cases();
    for (const auto& c : all)
        if (c.name == name) return c;
    throw std::runtime_error("no case " + name);
}

/// Area of a measured D on a specimen [m^2].
double area_of(double dc, const synth_photo::Scene& s)
{
    const double disc = synth_photo::kPi * s.R2 * s.R2;
    return disc + dc / 100.0 * (synth_photo::specimen_area(s) - disc);
}

/// The truth for a perspective model: the vertical projection (hem), or the
/// hem's image back-projected onto the plane z (disc-plane: 0, none: the
/// scale reference's height).
double true_area_for(const std::string& model, const synth_photo::Scene& s, double z_ref)
{
    if (model == "hem") return synth_photo::true_area(s);
    return synth_photo::plane_area(s, model == "none" ? z_ref : 0.0);
}

/// A CSV table (quoted cells allowed) as rows of column -> cell.
std::vector<std::map<std::string, std::string>> read_csv_table(const fs::path& file)
{
    auto split = [](const std::string& line) {
        std::vector<std::string> out(1);
        bool q = false;
        for (std::size_t i = 0; i < line.size(); ++i) {
            const char c = line[i];
            if (q && c == '"' && i + 1 < line.size() && line[i + 1] == '"') out.back() += '"', ++i;
            else if (c == '"') q = !q;
            else if (c == ',' && !q) out.emplace_back();
            else out.back() += c;
        }
        return out;
    };
    std::ifstream f(file);
    std::string line;
    std::getline(f, line);
    const auto header = split(line);
    std::vector<std::map<std::string, std::string>> rows;
    while (std::getline(f, line)) {
        const auto cells = split(line);
        std::map<std::string, std::string> r;
        for (std::size_t i = 0; i < header.size() && i < cells.size(); ++i) r[header[i]] = cells[i];
        rows.push_back(r);
    }
    return rows;
}

std::string one_decimal(double v)
{
    char b[32];
    std::snprintf(b, sizeof b, "%.1f", v);
    return b;
}

} // namespace

class TestPhoto : public QObject {
    Q_OBJECT
private slots:
    void cleanupTestCase() { fs::remove_all(fs::temp_directory_path() / ("drape_tst_photo_" + std::to_string(::getpid()))); }

    /// Every scene through `drape measure --top PHOTO ...`: measured within 1 %
    /// of the true area under each perspective model whose geometry is
    /// declared, or refused by the expected check with exit code 1 and no number.
    void scenes_data()
    {
        QTest::addColumn<QString>("name");
        for (const auto& c : synth_photo::cases()) QTest::newRow(c.name.c_str()) << QString::fromStdString(c.name);
    }
    void scenes()
    {
        QFETCH(QString, name);
        const auto& c = find_case(name.toStdString());
        const fs::path dir = temp_dir(c.name);
        const fs::path photo = synth_photo::write_photo(dir, c.scene);
        std::vector<std::string> args{"measure", "--top", photo.string(), "--json", "--overlay", (dir / "overlay.png").string()};
        args.insert(args.end(), c.flags.begin(), c.flags.end());
        const Run r = run_drape(args);
        QVERIFY2(r.code == 0 || r.code == 1, r.err.c_str());
        const json j = json::parse(r.out);
        QVERIFY(fs::file_size(dir / "overlay.png") > 10000); // the overlay shows what was counted, or why not
        if (!c.refusal.empty()) {
            QCOMPARE(r.code, 1);
            QVERIFY2(j["refused"].is_object(), r.out.substr(0, 400).c_str());
            QCOMPARE(j["refused"]["check"].get<std::string>(), c.refusal);
            QVERIFY(j["drape_coefficient_percent"].is_null()); // never a number
            QVERIFY(!j["refused"]["remedy"].get<std::string>().empty());
            QVERIFY2(r.err.find("refused (" + c.refusal + ")") != std::string::npos && r.err.find("what to try") != std::string::npos,
                     r.err.c_str());
            return;
        }
        QVERIFY2(r.code == 0, r.err.c_str());
        QVERIFY(j["refused"].is_null());
        const double D = j["drape_coefficient_percent"].get<double>();
        QVERIFY(D >= 0 && D <= 100);
        // The uncorrected value is always beside the corrected one.
        QVERIFY(j["drape_coefficient_uncorrected_percent"].is_number());
        const auto& pm = j["perspective_models"];
        const double z_ref = j["scale"]["reference_height_m"].get<double>();
        const bool height_known = j["scale"]["camera_height_known"].get<bool>();
        const std::string chosen = j["perspective"].get<std::string>();
        // The vertical projection, from an assumed camera height when it is not known.
        QCOMPARE(chosen, std::string("hem"));
        QCOMPARE(D, pm[chosen]["drape_coefficient_percent"].get<double>());
        for (const std::string model : {"none", "disc-plane", "hem"}) {
            QVERIFY(pm[model]["available"].get<bool>());
            const double dc = pm[model]["drape_coefficient_percent"].get<double>();
            const double a = area_of(dc, c.scene), truth = true_area_for(model, c.scene, z_ref);
            const double err = (a - truth) / truth;
            const double sigma = pm[model]["uncertainty_percent"].get<double>();
            const double dc_truth = (truth - synth_photo::kPi * c.scene.R2 * c.scene.R2) /
                                    (synth_photo::specimen_area(c.scene) - synth_photo::kPi * c.scene.R2 * c.scene.R2) * 100;
            qInfo("%-10s D %6.2f %% (true %6.2f) +- %.2f, area %+.2f %%", model.c_str(), dc, dc_truth, sigma, 100 * err);
            // From an assumed camera height the hem's area is as far off as the
            // height; its stated uncertainty must still cover the truth.
            if (!(model == "hem" && !height_known))
                QVERIFY2(std::abs(err) < c.area_tolerance, qPrintable(QString("%1: area off by %2 %").arg(model.c_str()).arg(100 * err)));
            QVERIFY2(std::abs(dc - dc_truth) <= 2 * sigma, // the stated uncertainty covers the error
                     qPrintable(QString("%1: D %2, true %3, +- %4").arg(model.c_str()).arg(dc).arg(dc_truth).arg(sigma)));
        }
        // Uncertainty terms name the unknowns.
        std::set<std::string> names;
        for (const auto& t : pm["hem"]["uncertainty_terms"]) names.insert(t["name"].get<std::string>());
        for (const char* n : {"edge", "scale", "camera_height", "hem_depth"}) QVERIFY2(names.count(n), n);
        if (!height_known) {
            // The hem model is reported with the assumed camera height and a wide band.
            QVERIFY(pm["hem"]["uncertainty_percent"].get<double>() > 3.0);
        }
    }

    /// Markers on the floor and the disc rim at the disc top: two heights give
    /// the camera height; a rotated and tilted camera is handled by the
    /// markers' pose.
    void camera_height_from_two_heights()
    {
        for (const std::string name : {"markers-floor", "rotated-camera", "chessboard-floor"}) {
            const auto& c = find_case(name);
            const fs::path dir = temp_dir(name);
            auto meta = synth_photo::meta(c.scene, name == "chessboard-floor" ? "chessboard" : "markers");
            synth_photo::write_record(dir, c.scene, meta);
            const auto m = capture::measure_record(record::read_record(dir));
            QVERIFY2(m.top.measured, m.not_measured.empty() ? "" : m.not_measured.back().c_str());
            QVERIFY(m.view && m.view->camera_height_known);
            const double H = m.view->camera_height, truth = c.scene.H;
            qInfo("%s: camera height %.0f +- %.0f mm (true %.0f), %s", name.c_str(), 1e3 * H, 1e3 * m.view->camera_height_sigma,
                  1e3 * truth, m.view->source_text.c_str());
            QVERIFY(std::abs(H - truth) < 2 * m.view->camera_height_sigma);
            QVERIFY(std::abs(H - truth) < 0.05 * truth);
            QVERIFY(m.view->camera_height_source.find("two heights") != std::string::npos);
            QCOMPARE(m.top.perspective, std::string("hem"));
            if (name == "rotated-camera") QVERIFY(m.view->source_text.find("tilted") != std::string::npos);
        }
    }

    /// px/mm of a ruler gives the same D as the disc rim; a wrong scale is refused.
    void px_per_mm_scale()
    {
        const auto& c = find_case("plain");
        const fs::path dir = temp_dir("pxmm");
        const double px_per_mm = c.scene.f / c.scene.H * 1e-3; // at the disc top
        auto meta = synth_photo::meta(c.scene, "px-per-mm");
        meta["top_photo"]["scale"]["px_per_mm"] = px_per_mm;
        meta["top_photo"]["camera_height_mm"] = 1e3 * c.scene.H;
        synth_photo::write_record(dir, c.scene, meta);
        const auto m = capture::measure_record(record::read_record(dir));
        QVERIFY(m.top.measured);
        const double D = m.top.metrics.drape_coefficient_percent;
        QVERIFY2(std::abs(D - synth_photo::true_dc(c.scene)) < 0.5, qPrintable(QString::number(D)));
        // A ruler read 30 % too small makes the drape look larger than the specimen.
        meta["top_photo"]["scale"]["px_per_mm"] = 0.7 * px_per_mm;
        std::ofstream(dir / "meta.json") << meta.dump();
        const auto bad = capture::measure_record(record::read_record(dir));
        QVERIFY(bad.refused.has_value());
        QVERIFY2(bad.refused->check == "search-limit" || bad.refused->check == "beyond-specimen", bad.refused->check.c_str());
    }

    /// A rectangle whose orientation is not given: estimated from the outline.
    void rectangle_orientation_from_the_photo()
    {
        const auto& c = find_case("rectangle");
        const fs::path dir = temp_dir("rect-auto");
        auto meta = synth_photo::meta(c.scene);
        meta["configuration"]["specimen"]["angle_deg"] = "auto";
        meta["top_photo"]["camera_height_mm"] = 1e3 * c.scene.H;
        synth_photo::write_record(dir, c.scene, meta);
        const auto m = capture::measure_record(record::read_record(dir));
        QVERIFY(m.top.measured);
        const double a = std::remainder(m.top.specimen_angle - c.scene.angle, synth_photo::kPi) * 180 / synth_photo::kPi;
        qInfo("angle %.1f deg (true %.1f), D %.2f (true %.2f)", m.top.specimen_angle * 180 / synth_photo::kPi,
              c.scene.angle * 180 / synth_photo::kPi, m.top.metrics.drape_coefficient_percent, synth_photo::true_dc(c.scene));
        QVERIFY(std::abs(a) < 3.0);
        QVERIFY(std::abs(m.top.metrics.drape_coefficient_percent - synth_photo::true_dc(c.scene)) < 1.0);
    }

    /// Manual overrides: a threshold, a complete user mask, a partial one.
    void manual_overrides()
    {
        const auto& dark = find_case("dark-on-dark");
        const fs::path dir = temp_dir("threshold");
        auto meta = synth_photo::meta(dark.scene);
        meta["top_photo"]["camera_height_mm"] = 700;
        meta["top_photo"]["threshold"] = "L<24";
        synth_photo::write_record(dir, dark.scene, meta);
        auto m = capture::measure_record(record::read_record(dir));
        QVERIFY(m.top.measured);
        QVERIFY(m.top.segmentation_method.find("threshold") != std::string::npos);
        QVERIFY2(std::abs(area_of(m.top.metrics.drape_coefficient_percent, dark.scene) / synth_photo::true_area(dark.scene) - 1) < 0.01,
                 qPrintable(QString::number(m.top.metrics.drape_coefficient_percent)));

        // The refused shadow case, measured with a mask drawn from the truth.
        const auto& sh = find_case("refused-shadow-as-dark-as-cloth");
        const fs::path d2 = temp_dir("mask");
        auto m2 = synth_photo::meta(sh.scene);
        m2["top_photo"]["camera_height_mm"] = 700;
        m2["top_photo"]["mask"] = "mask.png";
        synth_photo::write_record(d2, sh.scene, m2);
        const auto cam = synth_photo::camera(sh.scene);
        cv::Mat big = cv::Mat::zeros(sh.scene.height_px * 4, sh.scene.width_px * 4, CV_8U);
        std::vector<cv::Point> hem;
        for (int k = 0; k < 2880; ++k) {
            const double th = 2 * synth_photo::kPi * k / 2880, r = synth_photo::hem_r(sh.scene, th);
            const auto u = cam.project({r * std::cos(th), r * std::sin(th), synth_photo::hem_z(sh.scene, th)});
            hem.emplace_back(static_cast<int>(std::lround((u.x() * 4 + 1.5) * 16)), static_cast<int>(std::lround((u.y() * 4 + 1.5) * 16)));
        }
        cv::fillPoly(big, std::vector<std::vector<cv::Point>>{hem}, cv::Scalar(255), cv::LINE_8, 4);
        cv::Mat mask;
        cv::resize(big, mask, cv::Size(sh.scene.width_px, sh.scene.height_px), 0, 0, cv::INTER_AREA);
        mask = mask >= 128;
        cv::imwrite((d2 / "mask.png").string(), mask);
        m = capture::measure_record(record::read_record(d2));
        QVERIFY2(m.top.measured, m.refused ? m.refused->message.c_str() : "");
        QVERIFY(m.top.segmentation_method.find("user mask") != std::string::npos);
        const double err = area_of(m.top.metrics.drape_coefficient_percent, sh.scene) / synth_photo::true_area(sh.scene) - 1;
        QVERIFY2(std::abs(err) < 0.01, qPrintable(QString::number(err)));

        // A mask that is white all over: "cloth" covering most of the photo.
        cv::imwrite((d2 / "mask.png").string(), cv::Mat(mask.size(), CV_8U, cv::Scalar(255)));
        m = capture::measure_record(record::read_record(d2));
        QVERIFY(m.refused && m.refused->check == "region-size");
        // A mask of the flat specimen 2 % larger than declared, in the disc
        // plane: D over 100 % is refused, never printed.
        cv::Mat flat = cv::Mat::zeros(mask.size(), CV_8U);
        const auto c0 = cam.project({0, 0, 0});
        const double r_px = (cam.project({1.02 * sh.scene.R1, 0, 0}) - c0).norm();
        cv::circle(flat, cv::Point(static_cast<int>(c0.x()), static_cast<int>(c0.y())), static_cast<int>(r_px), cv::Scalar(255), cv::FILLED);
        cv::imwrite((d2 / "mask.png").string(), flat);
        m2["top_photo"]["perspective"] = "disc-plane";
        std::ofstream(d2 / "meta.json") << m2.dump();
        m = capture::measure_record(record::read_record(d2));
        QVERIFY2(m.refused && m.refused->check == "dc-range", m.refused ? m.refused->check.c_str() : "measured");
        QVERIFY(capture::to_json(m)["drape_coefficient_percent"].is_null());

        // A partial mask (grey = let the segmentation decide) only seeds it.
        cv::Mat scribble(mask.size(), CV_8U, cv::Scalar(128));
        const auto& pl = find_case("plain");
        const fs::path d3 = temp_dir("scribble");
        auto m3 = synth_photo::meta(pl.scene);
        m3["top_photo"]["camera_height_mm"] = 700;
        m3["top_photo"]["mask"] = "mask.png";
        synth_photo::write_record(d3, pl.scene, m3);
        cv::imwrite((d3 / "mask.png").string(), scribble);
        m = capture::measure_record(record::read_record(d3));
        QVERIFY(m.top.measured);
        QVERIFY(std::abs(m.top.metrics.drape_coefficient_percent - synth_photo::true_dc(pl.scene)) < 1.0);
    }

    /// The flags write the minimal meta.json; measuring the record it makes gives the same D.
    /// An outline that does not follow the cloth's edge: seeds that make GrabCut
    /// leave out a sector of the cloth (as a white knit's lit half on a cream floor
    /// was left out of a real photo) put the outline through the cloth there, where
    /// the colours either side nearly the same. The weak stretch is found, and D's
    /// uncertainty covers the truth (60 and 200 deg cut away: D 3 and 16 points
    /// low); with the cloth cut away all round the photo is refused (weak-outline).
    void weak_outline_widens_or_refuses_data()
    {
        QTest::addColumn<double>("sector_deg");
        QTest::addColumn<bool>("refused");
        QTest::newRow("60 deg cut away") << 60.0 << false;
        QTest::newRow("200 deg cut away") << 200.0 << false;
        QTest::newRow("cut away all round") << 360.0 << true;
    }
    void weak_outline_widens_or_refuses()
    {
        QFETCH(double, sector_deg);
        QFETCH(bool, refused);
        const auto& plain = find_case("plain");
        const fs::path dir = temp_dir("weak-outline-" + std::to_string(static_cast<int>(sector_deg)));
        auto meta = synth_photo::meta(plain.scene);
        meta["top_photo"]["camera_height_mm"] = 700;
        meta["top_photo"]["mask"] = "seeds.png";
        synth_photo::write_record(dir, plain.scene, meta);
        // Grey (GrabCut decides) everywhere but a black sector beyond 1.15 disc radii.
        const auto cam = synth_photo::camera(plain.scene);
        const auto c0 = cam.project({0, 0, 0});
        const double r_in = (cam.project({1.15 * plain.scene.R2, 0, 0}) - c0).norm();
        cv::Mat seeds(plain.scene.height_px, plain.scene.width_px, CV_8U, cv::Scalar(128));
        for (int y = 0; y < seeds.rows; ++y)
            for (int x = 0; x < seeds.cols; ++x) {
                const double dx = x - c0.x(), dy = y - c0.y();
                double a = std::atan2(dy, dx) * 180 / synth_photo::kPi;
                if (a < 0) a += 360;
                if (std::hypot(dx, dy) > r_in && a < sector_deg) seeds.at<uchar>(y, x) = 0;
            }
        cv::imwrite((dir / "seeds.png").string(), seeds);
        const auto m = capture::measure_record(record::read_record(dir));
        if (refused) {
            QVERIFY2(m.refused, qPrintable(QString("measured: weak %1, D %2 +- %3").arg(m.top.weak_outline_fraction).arg(m.top.metrics.drape_coefficient_percent).arg(m.top.dc_uncertainty_percent)));
            QCOMPARE(m.refused->check, std::string("weak-outline"));
            return;
        }
        QVERIFY2(m.top.measured, m.refused ? m.refused->message.c_str() : "");
        QVERIFY(m.top.segmentation_method.find("GrabCut") == 0);
        const double truth = (synth_photo::true_area(plain.scene) - synth_photo::kPi * plain.scene.R2 * plain.scene.R2) /
                             (synth_photo::specimen_area(plain.scene) - synth_photo::kPi * plain.scene.R2 * plain.scene.R2) * 100;
        const double D = m.top.metrics.drape_coefficient_percent, u = m.top.dc_uncertainty_percent;
        qInfo("weak outline %.0f %% of the rays; D %.2f +- %.2f, true %.2f", 100 * m.top.weak_outline_fraction, D, u, truth);
        QVERIFY(m.top.weak_outline_fraction > 0.05); // the cut stretch is found
        QVERIFY2(truth - D > 3.0, "the cut-away sector lowers D");
        QVERIFY2(std::abs(D - truth) <= 2 * u, qPrintable(QString("D %1 +- %2, true %3").arg(D).arg(u).arg(truth)));
    }

    void flags_write_the_minimal_record()
    {
        const auto& c = find_case("plain");
        const fs::path dir = temp_dir("write-meta");
        const fs::path photo = synth_photo::write_photo(dir, c.scene);
        const Run a = run_drape({"measure", "--top", photo.string(), "--disc", "180mm", "--specimen", "300mm", "--camera-height", "700mm",
                             "--write-meta", (dir / "meta.json").string(), "--json"});
        QCOMPARE(a.code, 0);
        const json meta = json::parse(std::ifstream(dir / "meta.json"));
        QCOMPARE(meta["top_photo"]["image"].get<std::string>(), std::string("photo.jpg"));
        QCOMPARE(meta["top_photo"]["scale"]["source"].get<std::string>(), std::string("disc"));
        const Run b = run_drape({"measure", dir.string(), "--json"});
        QCOMPARE(b.code, 0);
        QCOMPARE(json::parse(a.out)["drape_coefficient_percent"].get<double>(), json::parse(b.out)["drape_coefficient_percent"].get<double>());
        // Text output names the models and the scale.
        const Run t = run_drape({"measure", dir.string()});
        QVERIFY(t.out.find("uncorrected") != std::string::npos && t.out.find("disc rim") != std::string::npos);
        // Bad flags: exit 2 naming the flag.
        const Run u = run_drape({"measure", "--top", photo.string(), "--disc", "180mm"});
        QCOMPARE(u.code, 2);
        QVERIFY(u.err.find("--specimen") != std::string::npos);
        const Run v = run_drape({"measure", "--top", photo.string(), "--disc", "180mm", "--specimen", "300mm", "--scale", "ruler"});
        QCOMPARE(v.code, 2);
    }

    /// A folder of photos with one calibration: a table, progress, exit 1 when one is refused.
    void batch()
    {
        const fs::path dir = temp_dir("batch");
        for (const std::string name : {"plain", "print", "refused-off-photo"}) {
            auto s = find_case(name).scene;
            if (name == "refused-off-photo") s.H = 0.7, s.offset = {0.30, 0.0}; // same camera height, drape off the photo
            synth_photo::write_photo(dir / "photos", s, name + ".jpg");
        }
        const Run r = run_drape({"measure", "--batch", (dir / "photos").string(), "--disc", "180mm", "--specimen", "300mm", "--camera-height",
                             "700mm", "--table", (dir / "table.csv").string(), "--overlays", (dir / "overlays").string()});
        QCOMPARE(r.code, 1);
        QVERIFY2(r.err.find("[1/3]") != std::string::npos && r.err.find("[3/3]") != std::string::npos, r.err.c_str());
        std::ifstream f(dir / "table.csv");
        std::string line;
        std::vector<std::string> lines;
        while (std::getline(f, line)) lines.push_back(line);
        QCOMPARE(lines.size(), std::size_t(4));
        QVERIFY(lines[0].rfind("photo,status,check,drape_coefficient_percent", 0) == 0);
        QVERIFY2(lines[1].find("plain.jpg,measured") == 0, lines[1].c_str());
        QVERIFY2(lines[3].find("refused-off-photo.jpg,refused,border") == 0, lines[3].c_str());
        QVERIFY(fs::exists(dir / "overlays" / "refused-off-photo-overlay.png"));
        // JSON table.
        const Run j = run_drape({"measure", "--batch", (dir / "photos").string(), "--disc", "180mm", "--specimen", "300mm", "--camera-height",
                             "700mm", "--table", (dir / "table.json").string()});
        QCOMPARE(j.code, 1);
        const json t = json::parse(std::ifstream(dir / "table.json"));
        QCOMPARE(t["photos"].size(), std::size_t(3));
        QCOMPARE(t["photos"][0]["status"].get<std::string>(), std::string("measured"));
        QVERIFY(std::abs(t["photos"][0]["measurement"]["drape_coefficient_percent"].get<double>() -
                         synth_photo::true_dc(find_case("plain").scene)) < 1.0);
    }

    /// Lab records: the perspective model can be chosen, the photo segmenter
    /// used; the reported D follows.
    void lab_record_models()
    {
        synth::Spec s;
        const fs::path dir = temp_dir("lab");
        synth::write_record(dir, s);
        const auto rec = record::read_record(dir);
        capture::MeasureOptions opt;
        auto m = capture::measure_record(rec, opt);
        QCOMPARE(m.top.perspective, std::string("hem"));
        QCOMPARE(m.top.metrics.drape_coefficient_percent, m.top.hem.dc_percent);
        QCOMPARE(m.top.uncorrected.dc_percent, m.top.dc_plane_percent);
        opt.perspective = "none";
        m = capture::measure_record(rec, opt);
        QCOMPARE(m.top.metrics.drape_coefficient_percent, m.top.dc_plane_percent);
        opt.perspective = "calibration";
        opt.segmentation = "photo";
        m = capture::measure_record(rec, opt);
        QVERIFY(m.top.measured);
        QVERIFY(m.top.segmentation_method.find("GrabCut") != std::string::npos);
        QVERIFY2(std::abs(m.top.metrics.drape_coefficient_percent - synth::true_dc(s)) < 0.5,
                 qPrintable(QString::number(m.top.metrics.drape_coefficient_percent)));
    }

    /// The lens from the photo's EXIF (a phone's 35 mm equivalent focal length):
    /// the camera height follows from it (+-5 %) instead of an assumed lens
    /// (+-30 %); a block that is cut short or points outside itself is ignored
    /// with a warning, never read past its end.
    void exif_lens()
    {
        // APP1 "Exif" with IFD0 -> the EXIF directory -> FocalLengthIn35mmFilm.
        auto app1 = [](std::uint16_t f35, bool little) {
            std::vector<std::uint8_t> t;
            auto byte = [&](std::uint32_t v) { t.push_back(std::uint8_t(v & 0xff)); };
            auto u16 = [&](std::uint32_t v) {
                if (little) { byte(v); byte(v >> 8); }
                else { byte(v >> 8); byte(v); }
            };
            auto u32 = [&](std::uint32_t v) {
                if (little) { u16(v & 0xffff); u16(v >> 16); }
                else { u16(v >> 16); u16(v & 0xffff); }
            };
            byte(little ? 'I' : 'M');
            byte(little ? 'I' : 'M');
            u16(42); u32(8);
            u16(1); u16(0x8769); u16(4); u32(1); u32(26); u32(0); // IFD0: the EXIF directory at 26
            u16(1); u16(0xA405); u16(3); u32(1); u16(f35); u16(0); u32(0);
            const std::string head("\xFF\xE1\0\0Exif\0\0", 10);
            std::vector<std::uint8_t> seg(head.begin(), head.end());
            for (std::uint8_t b : t) seg.push_back(b);
            const std::size_t len = seg.size() - 2;
            seg[2] = std::uint8_t(len >> 8);
            seg[3] = std::uint8_t(len);
            return seg;
        };
        auto jpeg_with = [](const std::vector<std::uint8_t>& jpeg, const std::vector<std::uint8_t>& seg) {
            std::vector<std::uint8_t> out; // SOI, the segment, the rest
            out.reserve(jpeg.size() + seg.size());
            for (std::size_t i = 0; i < jpeg.size(); ++i) {
                if (i == 2)
                    for (std::uint8_t b : seg) out.push_back(b);
                out.push_back(jpeg[i]);
            }
            return out;
        };
        const auto& c = find_case("plain-unknown-height");
        std::vector<std::uint8_t> jpeg;
        cv::imencode(".jpg", synth_photo::render(c.scene), jpeg, {cv::IMWRITE_JPEG_QUALITY, 92});
        QVERIFY(!capture::exif_lens(jpeg).focal_35mm_mm); // OpenCV writes none
        // The scene's lens as a phone would round it: 1100 px on a 1600 px diagonal.
        const double f35 = std::round(c.scene.f / std::hypot(c.scene.width_px, c.scene.height_px) * std::hypot(36.0, 24.0));
        for (bool little : {true, false}) {
            const capture::ExifLens l = capture::exif_lens(jpeg_with(jpeg, app1(std::uint16_t(f35), little)));
            QVERIFY(l.focal_35mm_mm && l.warning.empty());
            QCOMPARE(*l.focal_35mm_mm, f35);
        }
        // Every cut of the block, and every byte of it flipped: no read past the end.
        const auto seg = app1(std::uint16_t(f35), true);
        for (std::size_t n = 4; n < seg.size(); ++n) {
            auto cut = std::vector<std::uint8_t>(seg.begin(), seg.begin() + long(n));
            cut[2] = std::uint8_t((n - 2) >> 8);
            cut[3] = std::uint8_t(n - 2);
            const capture::ExifLens l = capture::exif_lens(jpeg_with(jpeg, cut));
            QVERIFY(!l.focal_35mm_mm || n >= seg.size() - 6);
        }
        for (std::size_t i = 4; i < seg.size(); ++i) {
            auto bad = seg;
            bad[i] ^= 0xA5;
            (void)capture::exif_lens(jpeg_with(jpeg, bad));
        }
        // Through the command: the camera height from the EXIF lens, and D's interval
        // (+-5 % of the height) covering the truth, narrower than the assumed lens's.
        const fs::path dir = temp_dir("exif");
        const auto bytes = jpeg_with(jpeg, seg);
        std::ofstream(dir / "phone.jpg", std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), long(bytes.size()));
        std::ofstream(dir / "plain.jpg", std::ios::binary).write(reinterpret_cast<const char*>(jpeg.data()), long(jpeg.size()));
        auto measure = [&](const std::string& name) {
            std::vector<std::string> args{"measure", "--top", (dir / name).string(), "--json"};
            args.insert(args.end(), c.flags.begin(), c.flags.end());
            const Run r = run_drape(args);
            if (r.code != 0) qWarning("%s", r.err.c_str());
            return json::parse(r.out);
        };
        const json with_lens = measure("phone.jpg"), without = measure("plain.jpg");
        QVERIFY(with_lens["scale"]["camera_height_known"].get<bool>());
        QVERIFY2(with_lens["scale"]["camera_height_source"].get<std::string>().find("EXIF") != std::string::npos,
                 with_lens["scale"]["camera_height_source"].dump().c_str());
        QVERIFY(!without["scale"]["camera_height_known"].get<bool>());
        const double truth = synth_photo::true_dc(c.scene);
        const double D = with_lens["drape_coefficient_percent"].get<double>(), u = with_lens["drape_coefficient_uncertainty_percent"].get<double>();
        qInfo("EXIF %.0f mm: D %.2f +- %.2f %%, without %.2f +- %.2f %%, true %.2f %%", f35, D, u,
              without["drape_coefficient_percent"].get<double>(), without["drape_coefficient_uncertainty_percent"].get<double>(), truth);
        QVERIFY(std::abs(D - truth) <= 2 * u);
        QVERIFY(u < without["drape_coefficient_uncertainty_percent"].get<double>());
        // The camera height's own term: +-5 % against +-30 %.
        auto height_term = [](const json& m) {
            for (const auto& t : m["perspective_models"]["hem"]["uncertainty_terms"])
                if (t["name"] == "camera_height") return t["points_percent"].get<double>();
            return -1.0;
        };
        qInfo("camera height term: %.2f points with the EXIF lens, %.2f assumed", height_term(with_lens), height_term(without));
        QVERIFY(height_term(with_lens) >= 0 && height_term(with_lens) < 0.3 * height_term(without));
    }

    /// A lab's own top photo measured as a plain photo, the floor chessboard (at
    /// -120 mm) its only scale and no lens given: the lab's D (its calibrated rig's
    /// vertical projection, not this engine's) within 2 points or inside twice the
    /// stated uncertainty. One record whose cloth's colour spreads onto the lit floor
    /// in a rough segmentation (the disc centre was 50 mm off and the photo refused),
    /// one with a 30 mm overhang (D most sensitive to the unknown camera height).
    void lab_photo_with_floor_chessboard_only_data()
    {
        QTest::addColumn<QString>("record");
        QTest::newRow("DL-A04") << "set-a/DL-A04";
        QTest::newRow("DL-D1-240-180") << "set-d/DL-D1-240-180";
    }
    void lab_photo_with_floor_chessboard_only()
    {
        QFETCH(QString, record);
        // The costly lab-photo cases run in the slow entry tst_photo_lab_slow; the unit
        // run keeps one lab photo and the synthetic scenes of the same code.
        if (record.startsWith("set-d/") && !drape_test::slow_cases_enabled()) QSKIP("a slow case: tst_photo_lab_slow runs it");
        const fs::path rec = fs::path(DRAPE_SHARED_DIR) / "data/drape-lab" / record.toStdString();
        if (!fs::exists(rec / "meta.json")) QSKIP("the lab's records are not beside the repository");
        const json meta = json::parse(std::ifstream(rec / "meta.json"));
        const auto& cfg = meta["configuration"];
        const double lab_dc = meta["lab_drape_coefficient_percent"].get<double>();
        // Outside the record: only the photo and the flags are known.
        const fs::path dir = temp_dir("lab-photo-" + rec.filename().string());
        fs::copy_file(rec / "top.jpg", dir / "top.jpg", fs::copy_options::overwrite_existing);
        auto mm = [](double v) { return std::to_string(static_cast<int>(std::lround(v))) + "mm"; };
        const Run r = run_drape({"measure", "--top", (dir / "top.jpg").string(), "--disc", mm(cfg["support_disc_diameter_D2_mm"].get<double>()),
                                 "--specimen", mm(cfg["specimen_diameter_D1_mm"].get<double>()), "--scale", "chessboard", "--board", "6x11",
                                 "--square", "25mm", "--reference-height", "-120mm", "--json"});
        QVERIFY2(r.code == 0, r.err.c_str());
        const json j = json::parse(r.out);
        QVERIFY(!j["scale"]["camera_height_known"].get<bool>());
        QCOMPARE(j["perspective"].get<std::string>(), std::string("hem"));
        const double D = j["drape_coefficient_percent"].get<double>(), u = j["drape_coefficient_uncertainty_percent"].get<double>();
        qInfo("%s: D %.1f +- %.1f %%, the lab's %.1f %%", record.toUtf8().constData(), D, u, lab_dc);
        QVERIFY2(std::abs(D - lab_dc) <= std::max(2.0, 2 * u),
                 qPrintable(QString("D %1 +- %2, the lab's %3").arg(D).arg(u).arg(lab_dc)));
        // The rim is not found under this cloth: the centre is the cloth's centroid,
        // and the bound it is given holds the pedestal's axis as the lab's calibrated
        // top camera sees it (never read by the measurement), with a D term for it.
        const json& sc = j["scale"];
        QVERIFY(sc["disc_centre_source"].get<std::string>().rfind("centroid", 0) == 0);
        QVERIFY(sc["disc_centre_bound_m"].is_number() && sc["disc_centre_sigma_m"].is_number());
        const auto& cam = meta["cameras"]["top"];
        const auto& t = cam["t_world_to_cam_mm"];
        const double u0 = cam["fx"].get<double>() * t[0].get<double>() / t[2].get<double>() + cam["cx"].get<double>();
        const double v0 = cam["fy"].get<double>() * t[1].get<double>() / t[2].get<double>() + cam["cy"].get<double>();
        const double off_m = std::hypot(sc["disc_centre_px"][0].get<double>() - u0, sc["disc_centre_px"][1].get<double>() - v0) *
                             t[2].get<double>() * 1e-3 / cam["fx"].get<double>();
        qInfo("disc centre %.1f mm off the axis, bound %.1f mm", off_m * 1e3, sc["disc_centre_bound_m"].get<double>() * 1e3);
        QVERIFY(off_m <= sc["disc_centre_bound_m"].get<double>());
        bool has_term = false;
        for (const auto& term : j["perspective_models"]["hem"]["uncertainty_terms"]) has_term |= term["name"] == "disc_centre";
        QVERIFY(has_term);
    }

    /// --scale-from: the chessboard found once in a separate calibration photo of
    /// the same fixed camera (another drape on the same stand) gives a photo the D
    /// the chessboard in the photo itself gives, to the printed digits, through
    /// --top (text) and --batch (CSV); the output names the calibration photo. A
    /// calibration photo of another size is an error naming both photos and sizes.
    void scale_from_calibration_photo()
    {
        const auto& c = find_case("chessboard-floor");
        const fs::path dir = temp_dir("scale-from");
        const fs::path cal = synth_photo::write_photo(dir / "calibration", c.scene, "board.jpg");
        synth_photo::Scene s = c.scene; // another drape: same camera, same board
        s.nodes = 7;
        s.phase = 0.1;
        s.k0 = 0.6;
        const fs::path photo = synth_photo::write_photo(dir / "photos", s, "drape.jpg");
        auto with = [&](const std::vector<std::string>& head, const std::vector<std::string>& extra) {
            std::vector<std::string> v = head;
            v.insert(v.end(), c.flags.begin(), c.flags.end());
            v.insert(v.end(), extra.begin(), extra.end());
            return v;
        };
        const Run in_photo = run_drape(with({"measure", "--top", photo.string()}, {"--json"}));
        QVERIFY2(in_photo.code == 0, in_photo.err.c_str());
        const json j0 = json::parse(in_photo.out);
        const double D0 = j0["drape_coefficient_percent"].get<double>(), U0 = j0["drape_coefficient_uncertainty_percent"].get<double>();
        QVERIFY(j0["scale"]["calibration_photo"].is_null());
        qInfo("board in the photo: D %.2f +- %.2f %% (true %.2f)", D0, U0, synth_photo::true_dc(s));
        QVERIFY(std::abs(D0 - synth_photo::true_dc(s)) <= 2 * U0);

        const Run from = run_drape(with({"measure", "--top", photo.string()}, {"--scale-from", cal.string()}));
        QVERIFY2(from.code == 0, from.err.c_str());
        const std::string want = "drape coefficient  " + one_decimal(D0) + " % (+- " + one_decimal(U0) + ", perspective: hem)";
        QVERIFY2(from.out.find(want) != std::string::npos, (want + "\n" + from.out).c_str());
        QVERIFY2(from.out.find("mm squares in " + cal.string() + " at z = -120 mm") != std::string::npos, from.out.c_str());

        const Run batch = run_drape(with({"measure", "--batch", (dir / "photos").string()},
                                         {"--scale-from", cal.string(), "--table", (dir / "table.csv").string()}));
        QVERIFY2(batch.code == 0, batch.err.c_str());
        QVERIFY2(batch.err.find("scale for every photo: chessboard 6 x 4 inner corners") != std::string::npos &&
                     batch.err.find("found in " + cal.string() + " (1280 x 960 px)") != std::string::npos,
                 batch.err.c_str());
        const auto rows = read_csv_table(dir / "table.csv");
        QCOMPARE(rows.size(), std::size_t(1));
        QCOMPARE(rows[0].at("scale"), "chessboard in " + cal.string());
        const double Db = std::stod(rows[0].at("drape_coefficient_percent"));
        qInfo("board in %s: D %.2f %% (batch)", cal.string().c_str(), Db);
        QVERIFY2(std::abs(Db - D0) < 0.05, qPrintable(QString("D %1 with --scale-from, %2 in the photo").arg(Db).arg(D0)));

        // Another size: the calibration does not hold.
        cv::Mat small;
        cv::resize(cv::imread(cal.string()), small, {}, 0.5, 0.5, cv::INTER_AREA);
        const fs::path cal_small = dir / "calibration" / "board-small.png";
        cv::imwrite(cal_small.string(), small);
        const Run bad = run_drape(with({"measure", "--top", photo.string()}, {"--scale-from", cal_small.string()}));
        QCOMPARE(bad.code, 1);
        for (const std::string& part : {photo.string(), std::string("1280 x 960 px"), cal_small.string(), std::string("640 x 480 px")})
            QVERIFY2(bad.err.find(part) != std::string::npos, (part + "\n" + bad.err).c_str());
    }

    /// --manifest: per-photo disc and specimen sizes (a 150 mm disc with a 340 mm
    /// specimen, a 300 x 400 mm rectangle at 20 deg) reach their rows and their D;
    /// a photo the manifest does not list takes the command line's sizes (said
    /// once). A bad manifest stops the batch before any photo is measured, with no
    /// table written.
    void batch_manifest()
    {
        const fs::path dir = temp_dir("manifest");
        synth_photo::Scene plain = find_case("plain").scene;
        plain.H = 0.80;
        synth_photo::Scene big = plain;
        big.R2 = 0.075;
        big.R1 = 0.170;
        const synth_photo::Scene rect = find_case("rectangle").scene; // 300 x 400 mm at 20 deg, H 800 mm
        synth_photo::write_photo(dir / "photos", plain, "a-plain.jpg");
        synth_photo::write_photo(dir / "photos", big, "b-big.jpg");
        synth_photo::write_photo(dir / "photos", rect, "c-rect.jpg");
        std::ofstream(dir / "manifest.csv") << "photo,disc_mm,specimen_mm,specimen_angle_deg\n"
                                            << "b-big.jpg,150,340,\n"
                                            << "\"c-rect.jpg\",,300x400,20\n";
        const std::vector<std::string> base{"measure", "--batch", (dir / "photos").string(), "--disc", "180mm", "--specimen", "300mm",
                                            "--camera-height", "800mm"};
        auto with = [&](const std::vector<std::string>& extra) {
            auto v = base;
            v.insert(v.end(), extra.begin(), extra.end());
            return v;
        };
        const Run r = run_drape(with({"--manifest", (dir / "manifest.csv").string(), "--table", (dir / "table.csv").string()}));
        QVERIFY2(r.code == 0, r.err.c_str());
        QVERIFY2(r.err.find("1 of 3 photos are not in it and are measured with the command line's values (a-plain.jpg)") != std::string::npos,
                 r.err.c_str());
        const auto rows = read_csv_table(dir / "table.csv");
        QCOMPARE(rows.size(), std::size_t(3));
        const std::pair<const char*, const synth_photo::Scene*> truth[] = {{"a-plain.jpg", &plain}, {"b-big.jpg", &big}, {"c-rect.jpg", &rect}};
        const char* disc[] = {"180", "150", "180"};
        const char* spec[] = {"300", "340", "300x400 at 20 deg"};
        const char* line[] = {"", "2", "3"};
        for (std::size_t i = 0; i < 3; ++i) {
            const auto& row = rows[i];
            QCOMPARE(row.at("photo"), std::string(truth[i].first));
            QCOMPARE(row.at("status"), std::string("measured"));
            QCOMPARE(row.at("disc_mm"), std::string(disc[i]));
            QCOMPARE(row.at("specimen_mm"), std::string(spec[i]));
            QCOMPARE(row.at("manifest_line"), std::string(line[i]));
            // The rim found (the synthetic photos show it): no centroid, no bound.
            QVERIFY(row.at("centre_source").rfind("centroid", 0) != 0 && row.at("centre_bound_mm").empty());
            const double D = std::stod(row.at("drape_coefficient_percent")), u = std::stod(row.at("uncertainty_percent"));
            const double t = synth_photo::true_dc(*truth[i].second);
            qInfo("%s: D %.2f +- %.2f %% (true %.2f), disc %s mm, specimen %s", truth[i].first, D, u, t, disc[i], spec[i]);
            QVERIFY2(std::abs(D - t) <= std::min(2 * u, 2.0), qPrintable(QString("%1: D %2 +- %3, true %4").arg(truth[i].first).arg(D).arg(u).arg(t)));
        }
        // Bad manifests: an error naming the file, line, column and value; nothing measured, no table.
        const std::pair<std::string, std::string> bad[] = {
            {"photo,disc_mm,diameter_mm\nb-big.jpg,150,340\n", "manifest-bad.csv:1: column 3 'diameter_mm' is not a manifest column"},
            {"photo,disc_mm\nb-big.jpg,150\nd-none.jpg,150\n", "manifest-bad.csv:3: column 'photo': 'd-none.jpg' does not exist in"},
            {"photo,disc_mm\nb-big.jpg,15O\n", "manifest-bad.csv:2: column 'disc_mm': '15O' is not a number"},
            {"photo,specimen_angle_deg\nb-big.jpg,20\n", "manifest-bad.csv:2: column 'specimen_angle_deg': '20' turns a rectangle"},
        };
        for (const auto& [text, want] : bad) {
            std::ofstream(dir / "manifest-bad.csv") << text;
            const fs::path out = dir / "bad" / "table.csv";
            const Run b = run_drape(with({"--manifest", (dir / "manifest-bad.csv").string(), "--table", out.string()}));
            QCOMPARE(b.code, 1);
            QVERIFY2(b.err.find(want) != std::string::npos, (want + "\n" + b.err).c_str());
            QVERIFY2(b.err.find("[1/3]") == std::string::npos, b.err.c_str());
            QVERIFY(!fs::exists(out));
        }
    }

    /// --scale-from on the lab's photos (the same fixed camera for every record,
    /// the floor chessboard at -120 mm), in one batch: DL-D1-240-180's top.jpg as
    /// its own calibration photo gives exactly the D of the chessboard found in it
    /// (its sizes and disc centre from the manifest; measured second in the batch,
    /// so also after another photo); DL-A04's photo measured with that calibration
    /// photo gives the D of its own chessboard to the printed digits. (Two photos'
    /// corners differ by their noise: over the lab's twenty photos with one
    /// calibration photo, D moved by at most 0.054 points, px/mm by 0.025 %.)
    void lab_photos_with_one_calibration_photo()
    {
        if (!drape_test::slow_cases_enabled()) QSKIP("a slow case: tst_photo_lab_slow runs it (scale_from_calibration_photo covers the code)");
        const fs::path lab = fs::path(DRAPE_SHARED_DIR) / "data/drape-lab";
        const fs::path rec_a = lab / "set-a/DL-A04", rec_d = lab / "set-d/DL-D1-240-180";
        if (!fs::exists(rec_a / "top.jpg") || !fs::exists(rec_d / "top.jpg")) QSKIP("the lab's records are not beside the repository");
        const fs::path dir = temp_dir("lab-scale-from");
        fs::create_directories(dir / "photos");
        fs::create_directories(dir / "calibration");
        fs::copy_file(rec_a / "top.jpg", dir / "photos" / "DL-A04.jpg");
        fs::copy_file(rec_d / "top.jpg", dir / "photos" / "DL-D1-240-180.jpg");
        fs::copy_file(rec_d / "top.jpg", dir / "calibration" / "floor-board.jpg");
        const std::vector<std::string> board{"--scale", "chessboard", "--board", "6x11", "--square", "25mm", "--reference-height", "-120mm"};
        auto in_photo = [&](const std::string& name, const std::string& disc, const std::string& spec) {
            std::vector<std::string> v{"measure", "--top", (dir / "photos" / name).string(), "--disc", disc, "--specimen", spec, "--json"};
            v.insert(v.end(), board.begin(), board.end());
            const Run r = run_drape(v);
            if (r.code != 0) qWarning("%s", r.err.c_str());
            return json::parse(r.out);
        };
        const json a = in_photo("DL-A04.jpg", "150mm", "300mm"), d = in_photo("DL-D1-240-180.jpg", "180mm", "240mm");
        // The batch: the command line has DL-A04's sizes; the manifest DL-D1-240-180's, and its disc centre.
        const auto& cd = d["scale"]["disc_centre_px"];
        char centre[128];
        std::snprintf(centre, sizeof centre, "%.17g,%.17g", cd[0].get<double>(), cd[1].get<double>());
        std::ofstream(dir / "manifest.csv") << "photo,disc_mm,specimen_mm,centre_x_px,centre_y_px\nDL-D1-240-180.jpg,180,240," << centre << "\n";
        const std::string cal = (dir / "calibration" / "floor-board.jpg").string();
        std::vector<std::string> v{"measure", "--batch", (dir / "photos").string(), "--disc", "150mm", "--specimen", "300mm", "--scale-from", cal,
                                   "--manifest", (dir / "manifest.csv").string(), "--table", (dir / "table.json").string()};
        v.insert(v.end(), board.begin(), board.end());
        const Run r = run_drape(v);
        QVERIFY2(r.code == 0, r.err.c_str());
        const json t = json::parse(std::ifstream(dir / "table.json"));
        QCOMPARE(t["photos"].size(), std::size_t(2));
        const json& ra = t["photos"][0];
        const json& rd = t["photos"][1];
        QCOMPARE(ra["photo"].get<std::string>(), std::string("DL-A04.jpg"));
        QCOMPARE(ra["specimen_mm"].get<std::string>(), std::string("300"));
        QVERIFY(ra["manifest_line"].is_null());
        QCOMPARE(rd["specimen_mm"].get<std::string>(), std::string("240"));
        QCOMPARE(rd["disc_mm"].get<double>(), 180.0);
        QCOMPARE(rd["manifest_line"].get<int>(), 2);
        const json& ma = ra["measurement"];
        const json& md = rd["measurement"];
        for (const json* m : {&ma, &md}) {
            QCOMPARE((*m)["scale"]["calibration_photo"].get<std::string>(), cal);
            QVERIFY((*m)["scale"]["description"].get<std::string>().find("in " + cal + " at z = -120 mm") != std::string::npos);
        }
        QCOMPARE(md["scale"]["disc_centre_source"].get<std::string>(), std::string("declared (top_photo.disc_px)"));
        const double Da = ma["drape_coefficient_percent"].get<double>(), Dd = md["drape_coefficient_percent"].get<double>();
        const double Da0 = a["drape_coefficient_percent"].get<double>(), Dd0 = d["drape_coefficient_percent"].get<double>();
        qInfo("DL-D1-240-180 (its own photo as the calibration): D %.4f, board in the photo %.4f", Dd, Dd0);
        qInfo("DL-A04 (DL-D1-240-180's photo as the calibration): D %.4f, board in the photo %.4f; px/mm %.5f vs %.5f", Da, Da0,
              ma["scale"]["px_per_m"].get<double>() * 1e-3, a["scale"]["px_per_m"].get<double>() * 1e-3);
        QCOMPARE(Dd, Dd0); // the same pixels: the same corners, the same camera
        QCOMPARE(md["scale"]["px_per_m"].get<double>(), d["scale"]["px_per_m"].get<double>());
        // Another photo's corners carry their own pixel noise: the same D to well
        // within its uncertainty (not to the printed digit, which a rounding step
        // can split).
        QVERIFY(std::abs(Da - Da0) < 0.06);
        QVERIFY(std::abs(ma["drape_coefficient_uncertainty_percent"].get<double>() - a["drape_coefficient_uncertainty_percent"].get<double>()) < 0.06);
    }

    /// DRAPE_PHOTO_EXAMPLES=DIR writes every scene's photo and its flags (for
    /// the docs and for trying the command by hand).
    void write_examples()
    {
        const char* dir = std::getenv("DRAPE_PHOTO_EXAMPLES");
        if (!dir) QSKIP("DRAPE_PHOTO_EXAMPLES not set");
        for (const auto& c : synth_photo::cases()) {
            synth_photo::write_photo(fs::path(dir), c.scene, c.name + ".jpg");
            cv::Mat preview;
            cv::resize(cv::imread((fs::path(dir) / (c.name + ".jpg")).string()), preview, {}, 0.5, 0.5, cv::INTER_AREA);
            cv::imwrite((fs::path(dir) / ("preview-" + c.name + ".png")).string(), preview);
            std::ofstream f(fs::path(dir) / (c.name + ".flags"));
            for (const auto& x : c.flags) f << x << "\n";
            // The overlay as docs/capture.md shows it (480 px wide).
            std::vector<std::string> args{"measure", "--top", (fs::path(dir) / (c.name + ".jpg")).string(), "--overlay",
                                          (fs::path(dir) / (c.name + "-overlay-full.png")).string()};
            args.insert(args.end(), c.flags.begin(), c.flags.end());
            const Run r = run_drape(args);
            cv::Mat ov = cv::imread((fs::path(dir) / (c.name + "-overlay-full.png")).string());
            if (!ov.empty()) {
                cv::resize(ov, ov, {}, 480.0 / ov.cols, 480.0 / ov.cols, cv::INTER_AREA);
                cv::imwrite((fs::path(dir) / ("photo-" + c.name + ".png")).string(), ov, {cv::IMWRITE_PNG_COMPRESSION, 9});
            }
            qInfo("%s: exit %d", c.name.c_str(), r.code);
            qInfo("%s: true D %.2f %%, disc-plane %.2f %%", c.name.c_str(), synth_photo::true_dc(c.scene),
                  synth_photo::plane_dc(c.scene, 0.0));
        }
    }
};

QTEST_GUILESS_MAIN(TestPhoto)
#include "tst_photo.moc"
