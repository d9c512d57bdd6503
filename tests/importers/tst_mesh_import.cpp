// Importer tests on Debian's assimp-testmodels (/usr/share/assimp/models):
// counts, bounding boxes in metres, unit and up-axis conversion, node
// transforms, and clear errors on bad files.
#include "engine/core/error.hpp"
#include "importers/garment.hpp"
#include "importers/mesh_import.hpp"

#include <nlohmann/json.hpp>

#include <QByteArray>
#include <QFile>
#include <QTemporaryDir>
#include <Eigen/Geometry>
#include <QTest>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>

using namespace drape;
using namespace drape::importers;

namespace {

const std::string kModels = "/usr/share/assimp/models/";

std::string model(const std::string& rel)
{
    const std::string p = kModels + rel;
    if (!std::filesystem::exists(p)) qFatal("missing test model %s (install assimp-testmodels)", p.c_str());
    return p;
}

void write_bytes(const std::string& path, const std::string& bytes)
{
    std::ofstream f(path, std::ios::binary);
    f << bytes;
}

std::string read_bytes(const std::string& path)
{
    std::ifstream f(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(f), {});
}

/// The error must be a FileError whose message names the file.
template <class F>
QString expect_file_error(const std::string& path, F&& f)
{
    try {
        f();
    } catch (const FileError& e) {
        const QString msg = QString::fromStdString(e.what());
        if (!msg.contains(QString::fromStdString(path))) return "message does not name the file: " + msg;
        return {};
    } catch (const std::exception& e) {
        return QString("wrong exception type: ") + e.what();
    }
    return "no exception";
}

double triangle_area_sum(const cloth::Positions& X, const cloth::Triangles& F)
{
    double a = 0;
    for (int t = 0; t < F.rows(); ++t) {
        const Eigen::Vector3d p0 = X.row(F(t, 0)), p1 = X.row(F(t, 1)), p2 = X.row(F(t, 2));
        a += 0.5 * (p1 - p0).cross(p2 - p0).norm();
    }
    return a;
}

} // namespace

class TestMeshImport : public QObject {
    Q_OBJECT
private slots:
    void parsesUnitsAndAxes()
    {
        QCOMPARE(parse_unit("mm"), Unit::Millimetre);
        QCOMPARE(parse_unit("CM"), Unit::Centimetre);
        QCOMPARE(parse_unit("m"), Unit::Metre);
        QCOMPARE(parse_up_axis("Z"), UpAxis::Z);
        QVERIFY_THROWS_EXCEPTION(ParameterError, parse_unit("inch"));
        QVERIFY_THROWS_EXCEPTION(ParameterError, parse_up_axis("x"));
    }

    void makeHumanBodyInMetresZUp()
    {
        const std::string path = model("Collada/human.zae");
        const ImportedScene s = import_scene(path);
        QCOMPARE(s.meshes.size(), std::size_t(2));
        const ImportedMesh* body = s.find("human-baseMesh");
        QVERIFY(body);
        QVERIFY(s.find("human-highpolyeyesMesh"));
        // assimp reports 26756 triangles for the body; welding seams must not lose any.
        QCOMPARE(body->triangle_count(), 26756);
        QVERIFY(body->vertex_count() > 10000 && body->vertex_count() < 14517);
        const AlignedBox b = body->bounds();
        const Eigen::Vector3d size = b.size();
        qInfo("human body: %d vertices, %d triangles, bbox (%.4f %.4f %.4f)..(%.4f %.4f %.4f) m", body->vertex_count(),
              body->triangle_count(), b.min.x(), b.min.y(), b.min.z(), b.max.x(), b.max.y(), b.max.z());
        // An adult standing up: z is the tallest extent, 1.5..2.0 m, feet at z ~ 0.
        QVERIFY(size.z() > 1.5 && size.z() < 2.0);
        QVERIFY(size.z() > size.x() && size.z() > size.y());
        QVERIFY(std::abs(b.min.z()) < 0.02);
        // Left-right symmetric about x = 0.
        QVERIFY(std::abs(b.min.x() + b.max.x()) < 0.01 * size.x());
        // The head is at the top: the eyes sit in the top 10 % of the height.
        const AlignedBox eyes = s.find("human-highpolyeyesMesh")->bounds();
        QVERIFY(eyes.min.z() > b.max.z() - 0.1 * size.z());
        QCOMPARE(s.unit_source, std::string("file"));
    }

    void explicitUnitScalesTheFileNumbers()
    {
        const std::string path = model("Collada/human.zae");
        const ImportedScene m = import_scene(path, {Unit::Metre, UpAxis::File});
        const ImportedScene cm = import_scene(path, {Unit::Centimetre, UpAxis::File});
        const ImportedScene mm = import_scene(path, {Unit::Millimetre, UpAxis::File});
        QCOMPARE(cm.vertex_count(), m.vertex_count());
        const double hm = m.bounds().size().z(), hcm = cm.bounds().size().z(), hmm = mm.bounds().size().z();
        QVERIFY(std::abs(hcm / hm - 0.01) < 1e-6);
        QVERIFY(std::abs(hmm / hm - 0.001) < 1e-6);
        QCOMPARE(cm.unit_source, std::string("option"));

        // An OBJ declares no unit: metres assumed, and --unit mm shrinks by 1000.
        const std::string box = model("OBJ/box.obj");
        const ImportedScene b1 = import_scene(box);
        const ImportedScene b2 = import_scene(box, {Unit::Millimetre, UpAxis::File});
        QCOMPARE(b1.unit_source, std::string("assumed"));
        QVERIFY((b1.bounds().size() - Eigen::Vector3d::Ones()).norm() < 1e-6);
        QVERIFY((b2.bounds().size() - Eigen::Vector3d::Constant(1e-3)).norm() < 1e-9);
    }

    void upAxisRotatesIntoZUp()
    {
        // The same numbers read as y-up and as z-up: y-up (x, y, z) -> (x, -z, y).
        const std::string path = model("Collada/human.zae");
        const ImportedScene y = import_scene(path, {Unit::Metre, UpAxis::Y});
        const ImportedScene z = import_scene(path, {Unit::Metre, UpAxis::Z});
        const ImportedMesh& by = *y.find("human-baseMesh");
        const ImportedMesh& bz = *z.find("human-baseMesh");
        QCOMPARE(by.vertex_count(), bz.vertex_count());
        const double err = (by.X.col(0) - bz.X.col(0)).cwiseAbs().maxCoeff() +
                           (by.X.col(1) + bz.X.col(2)).cwiseAbs().maxCoeff() +
                           (by.X.col(2) - bz.X.col(1)).cwiseAbs().maxCoeff();
        QVERIFY(err < 1e-9);
        // Read as z-up, the body lies along y (tallest extent), as it would if
        // the user picked the wrong axis.
        const Eigen::Vector3d sz = bz.bounds().size();
        QVERIFY(sz.y() > sz.x() && sz.y() > sz.z());
        // The file's own declaration equals the explicit y.
        const ImportedScene f = import_scene(path);
        QVERIFY((f.find("human-baseMesh")->X - by.X).cwiseAbs().maxCoeff() < 1e-9);
        // The rotation keeps handedness: a closed body keeps a positive volume.
        auto volume = [](const ImportedMesh& m) {
            double v = 0;
            for (int t = 0; t < m.F.rows(); ++t) {
                const Eigen::Vector3d a = m.X.row(m.F(t, 0)), b = m.X.row(m.F(t, 1)), c = m.X.row(m.F(t, 2));
                v += a.dot(b.cross(c)) / 6.0;
            }
            return v;
        };
        const double vol = volume(by);
        qInfo("human body volume %.4f m^3", vol);
        QVERIFY(vol > 0.03 && vol < 0.15); // a human body of 1.66 m: tens of litres
        QVERIFY(std::abs(volume(bz) - vol) < 1e-6);
    }

    void formatsAgree()
    {
        // The same Wuson model as PLY and as STL: same welded mesh and box.
        const ImportedScene ply = import_scene(model("PLY/Wuson.ply"));
        const ImportedScene stl = import_scene(model("STL/Wuson.stl"));
        QCOMPARE(ply.triangle_count(), stl.triangle_count());
        QCOMPARE(ply.vertex_count(), stl.vertex_count());
        QVERIFY((ply.bounds().min - stl.bounds().min).norm() < 1e-6);
        QVERIFY((ply.bounds().max - stl.bounds().max).norm() < 1e-6);
        // glTF text and binary of the same box; 24 seam-split vertices weld to 8.
        const ImportedScene gl = import_scene(model("glTF2/BoxTextured-glTF/BoxTextured.gltf"));
        const ImportedScene glb = import_scene(model("glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"));
        QCOMPARE(gl.vertex_count(), 8);
        QCOMPARE(gl.triangle_count(), 12);
        QCOMPARE(glb.vertex_count(), 8);
        QVERIFY((gl.bounds().size() - Eigen::Vector3d::Ones()).norm() < 1e-6);
        QCOMPARE(gl.unit_source, std::string("file"));
        // Collada .dae and zipped .zae of the duck.
        const ImportedScene dae = import_scene(model("Collada/duck.dae"));
        const ImportedScene zae = import_scene(model("Collada/duck.zae"));
        QCOMPARE(dae.triangle_count(), zae.triangle_count());
        QVERIFY((dae.bounds().max - zae.bounds().max).norm() < 1e-9);
    }

    void fbxUnitScaleFactor()
    {
        // box.fbx declares UnitScaleFactor = 100 (cm per unit): one unit is a metre.
        const std::string path = model("FBX/box.fbx");
        const ImportedScene f = import_scene(path);
        QCOMPARE(f.unit_source, std::string("file"));
        QVERIFY(std::abs(f.unit_scale - 1.0) < 1e-9);
        const ImportedScene cm = import_scene(path, {Unit::Centimetre, UpAxis::File});
        QVERIFY((cm.bounds().size() * 100.0 - f.bounds().size()).norm() < 1e-6);
        // Meshes kept by name.
        const ImportedScene named = import_scene(model("FBX/cubes_with_names.fbx"));
        QVERIFY(named.meshes.size() > 1);
        for (const auto& m : named.meshes) QVERIFY(!m.name.empty());
        QVERIFY(named.find(named.meshes.front().name));
    }

    void nodeTransformsInstancingAndMerge()
    {
        // A glTF with one triangle instanced by two nodes: one translated,
        // one scaled by 2; written here so the expected numbers are known.
        QTemporaryDir dir;
        QVERIFY(dir.isValid());
        const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        const unsigned short idx[4] = {0, 1, 2, 0};
        QByteArray buf(reinterpret_cast<const char*>(pos), sizeof pos);
        buf.append(reinterpret_cast<const char*>(idx), sizeof idx);
        // Built with nlohmann::json rather than a raw string literal, which moc cannot read.
        using J = nlohmann::json;
        J g;
        g["asset"] = {{"version", "2.0"}};
        g["scene"] = 0;
        g["scenes"] = J::array({{{"nodes", {0, 1}}}});
        g["nodes"] = J::array({{{"name", "moved"}, {"mesh", 0}, {"translation", {1, 2, 3}}},
                               {{"name", "big"}, {"mesh", 0}, {"scale", {2, 2, 2}}}});
        g["meshes"] = J::array({{{"name", "tri"}, {"primitives", J::array({{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}})}}});
        g["buffers"] = J::array({{{"byteLength", 44},
                                  {"uri", "data:application/octet-stream;base64," + buf.toBase64().toStdString()}}});
        g["bufferViews"] = J::array({{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 36}},
                                     {{"buffer", 0}, {"byteOffset", 36}, {"byteLength", 6}}});
        g["accessors"] = J::array({{{"bufferView", 0}, {"componentType", 5126}, {"count", 3}, {"type", "VEC3"},
                                    {"min", {0, 0, 0}}, {"max", {1, 1, 0}}},
                                   {{"bufferView", 1}, {"componentType", 5123}, {"count", 3}, {"type", "SCALAR"}}});
        const std::string gltf = g.dump();
        const std::string path = dir.filePath("two.gltf").toStdString();
        write_bytes(path, gltf);
        const ImportedScene s = import_scene(path);
        QCOMPARE(s.meshes.size(), std::size_t(2));
        QVERIFY(s.find("tri") && s.find("tri#2"));
        // y-up -> z-up: (x, y, z) -> (x, -z, y). Moved: + (1, 2, 3) in y-up = (1, -3, 2).
        const ImportedMesh& moved = *s.find("tri");
        QVERIFY((moved.X.row(0) - Eigen::RowVector3d(1, -3, 2)).norm() < 1e-6);
        QVERIFY((moved.X.row(2) - Eigen::RowVector3d(1, -3, 3)).norm() < 1e-6);
        const ImportedMesh& big = *s.find("tri#2");
        QVERIFY((big.X.row(1) - Eigen::RowVector3d(2, 0, 0)).norm() < 1e-6);
        QVERIFY(std::abs(triangle_area_sum(big.X, big.F) - 2.0) < 1e-6);
        const ImportedMesh all = s.merged();
        QCOMPARE(all.vertex_count(), 6);
        QCOMPARE(all.triangle_count(), 2);
        QVERIFY(all.F.maxCoeff() == 5);
        QVERIFY_THROWS_EXCEPTION(ParameterError, s.merged({"nope"}));
        QCOMPARE(s.merged({"tri#2"}).triangle_count(), 1);

        // Imported garment -> cloth: same triangles and area.
        const cloth::ClothMesh c = garment_to_cloth(big);
        QCOMPARE(c.vertex_count(), 3);
        QVERIFY(std::abs(c.area() - 2.0) < 1e-6);
    }

    void badFilesGiveClearErrors()
    {
        QTemporaryDir dir;
        const auto tmp = [&](const char* n) { return dir.filePath(n).toStdString(); };
        // Missing and empty files.
        QCOMPARE(expect_file_error(tmp("missing.obj"), [&] { import_scene(tmp("missing.obj")); }), QString());
        const std::string empty = model("invalid/empty.obj");
        QCOMPARE(expect_file_error(empty, [&] { import_scene(empty); }), QString());
        // A format assimp does not read.
        const std::string txt = model("invalid/readme.txt");
        QCOMPARE(expect_file_error(txt, [&] { import_scene(txt); }), QString());
        // Truncated zipped Collada and binary glTF.
        const std::string zae = tmp("trunc.zae"), glb = tmp("trunc.glb"), stl = tmp("trunc.stl");
        const std::string full_zae = read_bytes(model("Collada/human.zae"));
        write_bytes(zae, full_zae.substr(0, full_zae.size() / 3));
        QCOMPARE(expect_file_error(zae, [&] { import_scene(zae); }), QString());
        const std::string full_glb = read_bytes(model("glTF2/BoxTextured-glTF-Binary/BoxTextured.glb"));
        write_bytes(glb, full_glb.substr(0, full_glb.size() / 2));
        QCOMPARE(expect_file_error(glb, [&] { import_scene(glb); }), QString());
        const std::string full_stl = read_bytes(model("STL/Spider_binary.stl"));
        write_bytes(stl, full_stl.substr(0, full_stl.size() / 2));
        QCOMPARE(expect_file_error(stl, [&] { import_scene(stl); }), QString());
        // Non-finite coordinates.
        const std::string inf = model("glTF2/BoxWithInfinites-glTF-Binary/BoxWithInfinites.glb");
        QCOMPARE(expect_file_error(inf, [&] { import_scene(inf); }), QString());
        const std::string nan_obj = tmp("nan.obj");
        write_bytes(nan_obj, "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
        QCOMPARE(expect_file_error(nan_obj, [&] { import_scene(nan_obj); }), QString());
        // Finite but absurd: a vertex 1e30 m out (float-finite, so it passed the NaN check) is a wrong unit or a
        // corrupt file; so is a node transform that scales a sane mesh there.
        const std::string far_obj = tmp("far.obj");
        write_bytes(far_obj, "v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n");
        QCOMPARE(expect_file_error(far_obj, [&] { import_scene(far_obj); }), QString());
        const std::string far_mm = tmp("far_mm.obj");
        write_bytes(far_mm, "v 0 0 0\nv 5e4 0 0\nv 0 1 0\nf 1 2 3\n"); // 50 km in metres ...
        QCOMPARE(expect_file_error(far_mm, [&] { import_scene(far_mm); }), QString());
        QCOMPARE(import_scene(far_mm, {Unit::Millimetre}).vertex_count(), 3); // ... 50 m in millimetres
        // Counts a header declares are checked against the file before assimp allocates for them (fuzz_mesh's
        // first finding: this OFF file, assimp's own test of the case, made `drape import` take 16 GB and 15 s).
        const std::string oom = model("invalid/OutOfMemory.off");
        QCOMPARE(expect_file_error(oom, [&] { import_scene(oom); }), QString());
        const std::string ply = tmp("many.ply");
        write_bytes(ply, "ply\nformat ascii 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\nproperty float z\n"
                         "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        QCOMPARE(expect_file_error(ply, [&] { import_scene(ply); }), QString());
        // An end_header word assimp does not recognise (followed by a vertical tab: fuzz_mesh) made its reader
        // look for the end of the header past the end of the file, forever.
        const std::string vt = tmp("vt.ply");
        write_bytes(vt, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                        "element face 1\nproperty list uchar int vertex_indices\nend_header\v\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        QCOMPARE(expect_file_error(vt, [&] { import_scene(vt); }), QString());
        // A list longer than its row: assimp sized it by the number before the entries (fuzz_mesh: an ASCII face
        // row '4444444444 7 6 5 4' made it ask for 3.8 GB). ASCII: the line holds 4 more values; binary: the rest
        // of the file holds 3 int entries, the face claims 0xFFFFFFFF.
        const std::string header = "element vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                                   "element face 1\nproperty list uint int vertex_indices\nend_header\n";
        const std::string long_ascii = tmp("long.ply");
        write_bytes(long_ascii, "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n0 1 0\n4444444444 7 6 5 4\n");
        QCOMPARE(expect_file_error(long_ascii, [&] { import_scene(long_ascii); }), QString());
        const std::string ok_ascii = tmp("ok.ply");
        write_bytes(ok_ascii, "ply\nformat ascii 1.0\n" + header + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
        QCOMPARE(import_scene(ok_ascii).vertex_count(), 3);
        std::string bin = "ply\nformat binary_little_endian 1.0\n" + header;
        const float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
        bin.append(reinterpret_cast<const char*>(xyz), sizeof xyz);
        const std::uint32_t face[4] = {3, 0, 1, 2};
        const std::string ok_bin = tmp("ok_bin.ply"), long_bin = tmp("long_bin.ply");
        write_bytes(ok_bin, bin + std::string(reinterpret_cast<const char*>(face), sizeof face));
        QCOMPARE(import_scene(ok_bin).vertex_count(), 3);
        const std::uint32_t bad_face[4] = {0xFFFFFFFFu, 0, 1, 2};
        write_bytes(long_bin, bin + std::string(reinterpret_cast<const char*>(bad_face), sizeof bad_face));
        QCOMPARE(expect_file_error(long_bin, [&] { import_scene(long_bin); }), QString());
        // An element declared twice: assimp sized its vertex array by the first and wrote the second's rows past
        // its end (fuzz_mesh, a heap overflow found by ASan at a later free; valgrind names the write).
        const std::string twice = tmp("twice.ply");
        write_bytes(twice, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                           "element vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
                           "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n"
                           "0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n");
        QCOMPARE(expect_file_error(twice, [&] { import_scene(twice); }), QString());
        // Meshes without faces: points only, a point cloud.
        const std::string pts = model("OBJ/testpoints.obj"), cloud = model("OBJ/point_cloud.obj");
        QCOMPARE(expect_file_error(pts, [&] { import_scene(pts); }), QString());
        QCOMPARE(expect_file_error(cloud, [&] { import_scene(cloud); }), QString());
        // Face indices out of range.
        const std::string bad_idx = model("invalid/malformed.obj");
        QCOMPARE(expect_file_error(bad_idx, [&] { import_scene(bad_idx); }), QString());
        // A Collada index list holding characters that are not numbers (fuzz_mesh: a run of '^' in a <polylist>'s
        // <p> made assimp append index 0 until it asked for 2 GiB) is refused by line before assimp reads it.
        const std::string caret = tmp("caret.dae");
        std::string duck = read_bytes(model("Collada/duck.dae"));
        const auto p = duck.find("<p>");
        QVERIFY(p != std::string::npos);
        duck.insert(p + 3, "0 ^^^^ ");
        write_bytes(caret, duck);
        QCOMPARE(expect_file_error(caret, [&] { import_scene(caret); }), QString());
        try {
            import_scene(caret);
        } catch (const FileError& e) {
            QVERIFY2(QString(e.what()).contains("the index list <p>") && QString(e.what()).contains("'^^^^'"), e.what());
        }
        // A <polylist> without its <vcount>: assimp read the polygon sizes from an empty list (SIGSEGV, fuzz_mesh).
        const std::string novcount = tmp("novcount.dae");
        std::string duck2 = read_bytes(model("Collada/duck.dae"));
        const auto v0 = duck2.find("<vcount>"), v1 = duck2.find("</vcount>");
        QVERIFY(v0 != std::string::npos && v1 != std::string::npos);
        duck2.erase(v0, v1 + 9 - v0);
        write_bytes(novcount, duck2);
        QCOMPARE(expect_file_error(novcount, [&] { import_scene(novcount); }), QString());
        // A <float_array> whose count is not its number of values: with count 0, assimp kept
        // an empty array and an accessor read it through a null pointer (SIGSEGV, fuzz_mesh).
        std::string cube = read_bytes(model("Collada/cube_triangulate.dae"));
        const auto c0 = cube.find("<float_array");
        QVERIFY(c0 != std::string::npos);
        const auto c1 = cube.find("count=\"", c0);
        const auto c2 = cube.find('"', c1 + 7);
        const std::string zero = tmp("count0.dae");
        write_bytes(zero, cube.substr(0, c1) + "count=\"0\"" + cube.substr(c2 + 1));
        QCOMPARE(expect_file_error(zero, [&] { import_scene(zero); }), QString());
        try {
            import_scene(zero);
        } catch (const FileError& e) {
            QVERIFY2(QString(e.what()).contains("declares count 0 but holds"), e.what());
        }
        // An accessor reading past its array (the array's count and values agree).
        const auto a0 = cube.find("<accessor");
        const auto a1 = cube.find("count=\"", a0);
        const auto a2 = cube.find('"', a1 + 7);
        const std::string far = tmp("accessor.dae");
        write_bytes(far, cube.substr(0, a1) + "count=\"1000\"" + cube.substr(a2 + 1));
        try {
            import_scene(far);
            QFAIL("an accessor past its array was imported");
        } catch (const FileError& e) {
            QVERIFY2(QString(e.what()).contains("<accessor> reads 1000"), e.what());
        }
        // Skin weights whose count is not their <vcount>'s: assimp read past its lists (SIGSEGV, fuzz_mesh).
        std::string skin = read_bytes(model("Collada/box_nested_animation.dae"));
        const auto w0 = skin.find("<vertex_weights count=\"8\"");
        QVERIFY(w0 != std::string::npos);
        skin.replace(w0, 25, "<vertex_weights count=\"4\"");
        const std::string weights = tmp("weights.dae");
        write_bytes(weights, skin);
        try {
            import_scene(weights);
            QFAIL("skin weights with the wrong count were imported");
        } catch (const FileError& e) {
            QVERIFY2(QString(e.what()).contains("<vertex_weights count=\"4\"> has 8 values in its <vcount>"), e.what());
        }
        QVERIFY(!import_scene(model("Collada/box_nested_animation.dae")).meshes.empty()); // the intact file still imports
    }
};

QTEST_APPLESS_MAIN(TestMeshImport)
#include "tst_mesh_import.moc"
