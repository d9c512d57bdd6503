// The one record reader: meta.json and contours.csv in SI units, every value
// inside a physical range, every file the record names inside the record.
#include "engine/core/error.hpp"
#include "engine/record/record.hpp"

#include <QTest>

#include <filesystem>
#include <fstream>

using namespace drape;
using nlohmann::json;
namespace fs = std::filesystem;

namespace {

json minimal_meta()
{
    return json::parse(R"({"specimen_id":"T1",
        "configuration":{"specimen_diameter_D1_mm":300,"support_disc_diameter_D2_mm":150,"pedestal_height_mm":120},
        "fabric":{"areal_density_g_m2":200,"thickness_mm":0.5},
        "contours":{"file":"contours.csv","theta_step_deg":10},
        "lab_drape_coefficient_percent":45.5})");
}

/// A record folder with meta.json and a contours.csv of `rows` (each "depth,theta,x,y").
fs::path make_record(const std::string& name, const json& meta, const std::vector<std::string>& rows)
{
    const fs::path d = fs::temp_directory_path() / ("drape_tst_record_" + std::to_string(::getpid())) / name;
    fs::create_directories(d);
    std::ofstream(d / "meta.json") << meta.dump(1);
    std::ofstream c(d / "contours.csv");
    c << "depth_mm,theta_deg,x_mm,y_mm\n";
    for (const auto& r : rows) c << r << "\n";
    return d;
}

std::vector<std::string> ring(double depth, double r, double step = 10)
{
    std::vector<std::string> out;
    for (double th = 0; th < 360 - 1e-9; th += step) {
        const double a = th * M_PI / 180;
        out.push_back(std::to_string(depth) + "," + std::to_string(th) + "," + std::to_string(r * std::cos(a)) + "," +
                      std::to_string(r * std::sin(a)));
    }
    return out;
}

template <class F>
QString file_error(F&& f)
{
    try {
        f();
    } catch (const FileError& e) {
        return QString::fromStdString(e.what());
    }
    return {};
}

} // namespace

class TestRecord : public QObject {
    Q_OBJECT
private slots:
    void cleanupTestCase() { fs::remove_all(fs::temp_directory_path() / ("drape_tst_record_" + std::to_string(::getpid()))); }

    void reads_meta_and_contours_in_si()
    {
        auto rows = ring(5, 110);
        const auto deeper = ring(10, 105);
        rows.insert(rows.end(), deeper.begin(), deeper.end());
        const fs::path d = make_record("ok", minimal_meta(), rows);
        const record::Record rec = record::read_record(d);
        QCOMPARE(rec.specimen_id, std::string("T1"));
        QCOMPARE(rec.R1, 0.15);
        QCOMPARE(rec.R2, 0.075);
        QCOMPARE(*rec.areal_density, 0.2);
        QCOMPARE(*rec.lab_drape_coefficient_percent, 45.5);
        const record::ContourStack st = record::read_contours(rec);
        QCOMPARE(st.depths.size(), std::size_t(2));
        QCOMPARE(st.depths[0], 0.005);
        QCOMPARE(st.profiles[0].size(), 36);
        QVERIFY(st.profiles[0].complete());
        QVERIFY(std::abs(st.profiles[1].r[3] - 0.105) < 1e-6);
    }

    void undeclared_ray_step_is_read_from_the_angles()
    {
        json meta = minimal_meta();
        meta["contours"].erase("theta_step_deg");
        const fs::path d = make_record("infer", meta, ring(5, 110, 5));
        const record::ContourStack st = record::read_contours(record::read_record(d));
        QCOMPARE(st.profiles[0].size(), 72);
        QVERIFY(st.profiles[0].complete());
    }

    void files_named_by_a_record_stay_inside_it()
    {
        for (const std::string bad : {"../../../../etc/passwd", "/etc/passwd", "sub/../../x.csv"}) {
            json meta = minimal_meta();
            meta["contours"]["file"] = bad;
            const fs::path d = make_record("escape", meta, ring(5, 110));
            const QString e = file_error([&] { record::read_contours(record::read_record(d)); });
            QVERIFY2(e.contains(QString::fromStdString(bad)) && (e.contains("absolute") || e.contains("..")), qPrintable(e));
        }
        // A symbolic link inside the folder that leads out of it.
        json meta = minimal_meta();
        meta["contours"]["file"] = "link.csv";
        const fs::path d = make_record("symlink", meta, ring(5, 110));
        fs::remove(d / "link.csv");
        fs::create_symlink("/etc/passwd", d / "link.csv");
        const QString e = file_error([&] { record::read_contours(record::read_record(d)); });
        QVERIFY2(e.contains("leads out of the record folder"), qPrintable(e));
    }

    void impossible_values_are_refused_by_line_and_field()
    {
        struct Case {
            const char* name;
            std::vector<std::string> rows;
            const char* expect;
        };
        const std::vector<Case> cases = {
            {"huge", {"5,0,1e308,0"}, "x_mm, y_mm: the point (1e+308, 0) mm lies 1e+308 mm from the axis, outside [37.5, 180]"},
            {"nan", {"5,0,nan,0"}, "column 'x_mm': 'nan' is not a number"},
            {"inf", {"5,0,110,-inf"}, "column 'y_mm': '-inf' is not a number"},
            {"far", {"5,0,0,181"}, "lies 181 mm from the axis"}, // 1.2 specimen radii is 180 mm
            {"zero", {"5,0,0,0"}, "outside"},
            {"depth", {"-5,0,110,0"}, "depth_mm"},
            {"theta", {"5,1e300,110,0"}, "theta_deg"},
            {"text", {"5,0,81.5abc,0"}, "'81.5abc' is not a number"},
            {"offgrid", {"5,3,110,0"}, "not on the regular"},
            {"twice", {"5,0,110,0", "5,0,111,0"}, "appears twice"},
        };
        for (const auto& c : cases) {
            const fs::path d = make_record(c.name, minimal_meta(), c.rows);
            const QString e = file_error([&] { record::read_contours(record::read_record(d)); });
            QVERIFY2(e.contains("contours.csv:") && e.contains(c.expect), qPrintable(QString(c.name) + ": " + e));
        }
        // Within 1.2 specimen radii a point is read (a specimen laid off centre).
        const fs::path near = make_record("reach", minimal_meta(), ring(5, 179));
        QCOMPARE(record::read_contours(record::read_record(near)).profiles[0].size(), 36);
        // meta.json fields out of their physical range.
        struct MetaCase {
            const char* field;
            json value;
        };
        for (const auto& mc : std::vector<MetaCase>{{"lab_drape_coefficient_percent", 1e6},
                                                    {"configuration.specimen_diameter_D1_mm", -300},
                                                    {"fabric.areal_density_g_m2", 1e302},
                                                    {"contours.theta_step_deg", 1e-9},
                                                    {"contours.repeatability_sigma_mm", -1}}) {
            json meta = minimal_meta();
            const std::string f = mc.field;
            const auto dot = f.find('.');
            if (dot == std::string::npos) meta[f] = mc.value;
            else meta[f.substr(0, dot)][f.substr(dot + 1)] = mc.value;
            const QString e = file_error([&] { record::parse_meta(meta.dump(), "/tmp/x", "x/meta.json"); });
            QVERIFY2(e.contains("x/meta.json") && e.contains(QString::fromStdString(f)), qPrintable(QString(mc.field) + ": " + e));
        }
    }

    /// Camera values and sizes are bounded before anything is allocated or
    /// drawn from them (fx = 1e300 crashed OpenCV's drawing with exit 3).
    void cameras_and_sizes_are_bounded()
    {
        const json camera = json::parse(R"({"image":"top.jpg","width":1152,"height":872,"fx":1280,"fy":1280,"cx":575.5,"cy":435.5,
            "dist_coeffs":[0,0,0,0,0],"R_world_to_cam":[[1,0,0],[0,-1,0],[0,0,-1]],"t_world_to_cam_mm":[0,0,880]})");
        json ok = minimal_meta();
        ok["cameras"]["top"] = camera;
        QCOMPARE(record::parse_meta(ok.dump(), "/tmp/x", "m.json").cameras.at("top").fx, 1280.0);
        struct Case {
            const char* key;
            json value;
            const char* field;
        };
        for (const auto& c : std::vector<Case>{{"fx", 1e300, "cameras.top.fx"},
                                               {"fy", 0.5, "cameras.top.fy"},
                                               {"cx", -1e300, "cameras.top.cx"},
                                               {"cy", 1e9, "cameras.top.cy"},
                                               {"t_world_to_cam_mm", json::array({0, 0, 1e300}), "cameras.top.t_world_to_cam_mm[2]"},
                                               {"dist_coeffs", json::array({1e300, 0, 0, 0, 0}), "cameras.top.dist_coeffs[0]"},
                                               {"width", 20000, "cameras.top.width"}}) {
            json meta = ok;
            meta["cameras"]["top"][c.key] = c.value;
            if (std::string(c.key) == "width") meta["cameras"]["top"]["height"] = 20000; // 400 megapixels
            const QString e = file_error([&] { record::parse_meta(meta.dump(), "/tmp/x", "m.json"); });
            QVERIFY2(e.contains(QString("'") + c.field + "'") && (e.contains("outside") || e.contains("megapixels")),
                     qPrintable(QString(c.key) + ": " + e));
        }
        // Contour levels: at most 1000 declared, and depths x rays before the profiles are allocated.
        json many = minimal_meta();
        many["contours"]["depths_mm"] = std::vector<double>(1001, 5.0);
        QVERIFY(file_error([&] { record::parse_meta(many.dump(), "/tmp/x", "m.json"); }).contains("more than 1000"));
        std::string csv = "depth_mm,theta_deg,x_mm,y_mm\n";
        for (int i = 0; i < 200; ++i) csv += std::to_string(1 + i * 0.1) + ",0,100,0\n";
        const QString e = file_error([&] { record::parse_contours(csv, "c.csv", 0.01, 0.15, 0.075, 0.12); });
        QVERIFY2(e.contains("200 depths x 36000 rays") && e.contains("this reader allocates"), qPrintable(e));
        // A cell echoed in a message is printable: no raw escape sequence reaches the terminal.
        std::string msg;
        try {
            record::parse_contours("depth_mm,theta_deg,x_mm,y_mm\n5,0,\x1b[2J\xff,0\n", "c.csv", 10, 0.15, 0.075, 0.12);
        } catch (const FileError& ex) {
            msg = ex.what();
        }
        QVERIFY2(msg.find("'\\x1B[2J\\xFF' is not a number") != std::string::npos && msg.find('\x1b') == std::string::npos, msg.c_str());
    }

    /// Names that cannot be resolved are refused (fail closed), not trusted.
    void unresolvable_names_are_refused()
    {
        json meta = minimal_meta();
        meta["contours"]["file"] = "loop.csv";
        const fs::path d = make_record("loop", meta, ring(5, 110));
        fs::create_symlink(d / "loop2.csv", d / "loop.csv");
        fs::create_symlink(d / "loop.csv", d / "loop2.csv");
        QVERIFY(!file_error([&] { record::read_contours(record::read_record(d)); }).isEmpty());
        meta["contours"]["file"] = "contours.csv\ncontours.csv";
        const fs::path d2 = make_record("ctrl", meta, ring(5, 110));
        QVERIFY(file_error([&] { record::read_contours(record::read_record(d2)); }).contains("control character"));
        // The folder itself is named as such, not as a symbolic link out (issue 55).
        for (const std::string dot : {".", "./", "./.", "sub/.."}) {
            meta["contours"]["file"] = dot;
            const fs::path d3 = make_record("dot", meta, ring(5, 110));
            const QString e = file_error([&] { record::read_contours(record::read_record(d3)); });
            QVERIFY2(!e.contains("symbolic link") && (e.contains("names the record folder itself") || e.contains("'..'")),
                     qPrintable(QString::fromStdString(dot) + ": " + e));
        }
        meta["contours"]["file"] = "here.csv";
        const fs::path d4 = make_record("dotlink", meta, ring(5, 110));
        fs::create_directory_symlink(".", d4 / "here.csv");
        const QString e4 = file_error([&] { record::read_contours(record::read_record(d4)); });
        QVERIFY2(e4.contains("through a symbolic link") && e4.contains("the record folder itself"), qPrintable(e4));
    }

    void missing_pieces_are_named()
    {
        QVERIFY(file_error([] { record::read_record("/nonexistent/record"); }).contains("not a record folder"));
        const fs::path d = fs::temp_directory_path() / ("drape_tst_record_" + std::to_string(::getpid())) / "empty";
        fs::create_directories(d);
        QVERIFY(file_error([&] { record::read_record(d); }).contains("meta.json"));
        json meta = minimal_meta();
        meta["configuration"].erase("specimen_diameter_D1_mm");
        const QString e = file_error([&] { record::parse_meta(meta.dump(), d, "m.json"); });
        QVERIFY2(e.contains("'configuration.specimen_diameter_D1_mm' is missing"), qPrintable(e));
    }

    void specimens_of_any_shape()
    {
        // A rectangle: D's denominator is its area, the search reaches its corners.
        json meta = minimal_meta();
        meta["configuration"].erase("specimen_diameter_D1_mm");
        meta["configuration"]["specimen"] = {{"shape", "rectangle"}, {"width_mm", 300}, {"length_mm", 400}, {"angle_deg", 90}};
        const auto rec = record::parse_meta(meta.dump(), "/tmp/x", "m.json");
        QCOMPARE(rec.specimen.shape, record::Specimen::Shape::Rectangle);
        QVERIFY(std::abs(rec.specimen.area() - 0.12) < 1e-12);
        QVERIFY(std::abs(rec.R1 - std::sqrt(0.12 / M_PI)) < 1e-12); // the equal-area radius the round formulas take
        // Rotated by 90 deg: the 400 mm side lies along x.
        QVERIFY(std::abs(rec.specimen.reach(0) - 0.200) < 1e-9);
        QVERIFY(std::abs(rec.specimen.reach(M_PI / 2) - 0.150) < 1e-9);
        QVERIFY(std::abs(rec.specimen.max_reach() - 0.250) < 1e-9);
        QVERIFY(rec.specimen.describe().find("300 x 400") != std::string::npos);
        // "auto": the orientation comes from the photo.
        meta["configuration"]["specimen"]["angle_deg"] = "auto";
        QVERIFY(record::parse_meta(meta.dump(), "/tmp/x", "m.json").specimen.angle_from_photo);
        // A square and a polygon (a hexagon of circumradius 160 mm).
        meta["configuration"]["specimen"] = {{"shape", "square"}, {"side_mm", 300}};
        QVERIFY(std::abs(record::parse_meta(meta.dump(), "/tmp/x", "m.json").specimen.area() - 0.09) < 1e-12);
        json hex = json::array();
        for (int k = 0; k < 6; ++k) hex.push_back({160 * std::cos(k * M_PI / 3), 160 * std::sin(k * M_PI / 3)});
        meta["configuration"]["specimen"] = {{"shape", "polygon"}, {"points_mm", hex}};
        const auto hr = record::parse_meta(meta.dump(), "/tmp/x", "m.json");
        QVERIFY(std::abs(hr.specimen.area() - 1.5 * std::sqrt(3.0) * 0.16 * 0.16) < 1e-9);
        QVERIFY(std::abs(hr.specimen.reach(0) - 0.160) < 1e-9);
        QVERIFY(std::abs(hr.specimen.reach(M_PI / 6) - 0.16 * std::cos(M_PI / 6)) < 1e-9);
        // A specimen that does not cover the disc, a polygon not around the
        // centre, an unknown shape: errors naming the field.
        meta["configuration"]["specimen"] = {{"shape", "rectangle"}, {"width_mm", 140}, {"length_mm", 400}};
        QVERIFY(file_error([&] { record::parse_meta(meta.dump(), "/tmp/x", "m.json"); }).contains("must cover the disc"));
        json off = json::array({json::array({100, 100}), json::array({300, 100}), json::array({200, 300})});
        meta["configuration"]["specimen"] = {{"shape", "polygon"}, {"points_mm", off}};
        QVERIFY(file_error([&] { record::parse_meta(meta.dump(), "/tmp/x", "m.json"); }).contains("does not enclose the disc centre"));
        meta["configuration"]["specimen"] = {{"shape", "oval"}};
        QVERIFY(file_error([&] { record::parse_meta(meta.dump(), "/tmp/x", "m.json"); }).contains("configuration.specimen.shape"));
        // Round given twice must agree.
        meta = minimal_meta();
        meta["configuration"]["specimen"] = {{"shape", "round"}, {"diameter_mm", 280}};
        QVERIFY(file_error([&] { record::parse_meta(meta.dump(), "/tmp/x", "m.json"); }).contains("disagrees"));
    }

    void single_camera_top_photo()
    {
        // The minimal single-camera record: disc, specimen, a photo, a scale source.
        const json minimal = json::parse(R"({"configuration": {"support_disc_diameter_D2_mm": 180, "specimen_diameter_D1_mm": 300},
                                             "top_photo": {"image": "photo.jpg", "scale": {"source": "disc"}}})");
        const auto rec = record::parse_meta(minimal.dump(), "/tmp/x", "m.json");
        QVERIFY(rec.top_photo.has_value());
        QVERIFY(rec.single_camera());
        QCOMPARE(rec.top_image(), std::string("photo.jpg"));
        QCOMPARE(rec.top_photo->scale, record::ScaleSource::Disc);
        QVERIFY(rec.unknown_fields.empty());
        QCOMPARE(rec.specimen_id, std::string("x")); // the folder's name
        // Every field, in SI.
        json full = minimal;
        full["top_photo"] = json::parse(R"({"image": "p.jpg",
            "scale": {"source": "markers", "size_mm": 50, "height_mm": -120, "height_sigma_mm": 2, "dictionary": "DICT_5X5_100",
                      "layout_mm": {"0": [-200, 200], "7": [200, -200]}},
            "disc_px": {"centre": [640, 480], "radius": 141.5}, "camera_height_mm": 700, "camera_height_sigma_mm": 10,
            "focal_px": 1100, "perspective": "hem", "mask": "mask.png", "threshold": "L<60"})");
        const auto f = record::parse_meta(full.dump(), "/tmp/x", "m.json").top_photo.value();
        QCOMPARE(f.scale, record::ScaleSource::Markers);
        QCOMPARE(f.marker_size, 0.05);
        QCOMPARE(f.reference_height, -0.12);
        QCOMPARE(*f.reference_height_sigma, 0.002);
        QCOMPARE(f.marker_dictionary, std::string("DICT_5X5_100"));
        QCOMPARE(f.marker_layout.size(), std::size_t(2));
        QVERIFY((f.marker_layout.at(7) - Eigen::Vector2d(0.2, -0.2)).norm() < 1e-12);
        QCOMPARE(*f.disc_radius_px, 141.5);
        QCOMPARE(*f.camera_height, 0.7);
        QCOMPARE(*f.focal_px, 1100.0);
        QCOMPARE(f.perspective, std::string("hem"));
        // px-per-mm, chessboard, calibration.
        json p = minimal;
        p["top_photo"]["scale"] = {{"source", "px-per-mm"}, {"px_per_mm", 4.2}};
        QCOMPARE(*record::parse_meta(p.dump(), "/tmp/x", "m.json").top_photo->px_per_mm, 4.2);
        p["top_photo"]["scale"] = {{"source", "chessboard"}, {"inner_corners", {9, 6}}, {"square_mm", 20}};
        QCOMPARE(record::parse_meta(p.dump(), "/tmp/x", "m.json").top_photo->board_cols, 9);
        // Bad declarations name their field.
        struct Bad {
            json scale;
            const char* expect;
        };
        for (const auto& b : std::vector<Bad>{{{{"source", "ruler"}}, "top_photo.scale.source"},
                                               {{{"source", "markers"}}, "top_photo.scale.size_mm"},
                                               {{{"source", "px-per-mm"}, {"px_per_mm", -3}}, "top_photo.scale.px_per_mm"},
                                               {{{"source", "chessboard"}, {"inner_corners", {9.5, 6}}, {"square_mm", 20}}, "inner_corners"},
                                               {{{"source", "calibration"}}, "cameras.top"},
                                               {{{"source", "markers"}, {"size_mm", 50}, {"layout_mm", {{"x", {0, 0}}}}}, "layout_mm.x"}}) {
            json m = minimal;
            m["top_photo"]["scale"] = b.scale;
            const QString e = file_error([&] { record::parse_meta(m.dump(), "/tmp/x", "m.json"); });
            QVERIFY2(e.contains(b.expect), qPrintable(e));
        }
        json q = minimal;
        q["top_photo"]["perspective"] = "fisheye";
        QVERIFY(file_error([&] { record::parse_meta(q.dump(), "/tmp/x", "m.json"); }).contains("top_photo.perspective"));
        q = minimal;
        q["top_photo"]["image"] = "../elsewhere/photo.jpg";
        QVERIFY(file_error([&] { record::parse_meta(q.dump(), "/tmp/x", "m.json"); }).contains("climbs out"));
        q = minimal;
        q["top_photo"]["mask"] = "/etc/mask.png";
        QVERIFY(file_error([&] { record::parse_meta(q.dump(), "/tmp/x", "m.json"); }).contains("absolute"));
        // A lab record (cameras, no top_photo) is not single-camera.
        QVERIFY(!record::parse_meta(minimal_meta().dump(), "/tmp/x", "m.json").single_camera());
    }
};

QTEST_APPLESS_MAIN(TestRecord)
#include "tst_record.moc"
