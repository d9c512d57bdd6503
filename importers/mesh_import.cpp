#include "importers/mesh_import.hpp"

#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#include <Eigen/LU>
#include <assimp/BaseImporter.h>
#include <assimp/Importer.hpp>
#include <assimp/ai_assert.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <optional>
#include <array>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <functional>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <unordered_map>
#include <vector>

// Debian's assimp is built with its assertions on, and a failed one calls
// abort(): a corrupt Collada file killed `drape import` (SIGABRT) in
// ColladaLoader.cpp:1743 (fuzz_mesh). This definition replaces the library's
// (ELF symbol interposition: the executable's definition wins) and throws
// instead; assimp's BaseImporter::ReadFile catches std::exception from a
// reader and reports a failed import, which import_scene turns into a
// FileError naming the file.
namespace Assimp {
void aiAssertViolation(const char* failed_expression, const char* file, int line)
{
    throw std::runtime_error(std::string("assimp's check '") + failed_expression + "' failed (" + file + ":" + std::to_string(line) +
                             ")");
}
} // namespace Assimp

namespace drape::importers {

namespace {

double unit_metres(Unit u)
{
    switch (u) {
    case Unit::Millimetre: return 1e-3;
    case Unit::Centimetre: return 1e-2;
    case Unit::Metre: return 1.0;
    case Unit::File: break;
    }
    return 1.0;
}

template <class T>
bool meta_get(const aiScene* s, const char* key, T& out)
{
    return s->mMetaData && s->mMetaData->Get(key, out);
}

/// Numeric metadata that FBX stores as int, float or double depending on the exporter.
bool meta_number(const aiScene* s, const char* key, double& out)
{
    if (!s->mMetaData) return false;
    const aiMetadataEntry* e = nullptr;
    for (unsigned i = 0; i < s->mMetaData->mNumProperties; ++i)
        if (std::string(s->mMetaData->mKeys[i].C_Str()) == key) e = &s->mMetaData->mValues[i];
    if (!e || !e->mData) return false;
    switch (e->mType) {
    case AI_INT32: out = *static_cast<const int32_t*>(e->mData); return true;
    case AI_UINT64: out = static_cast<double>(*static_cast<const uint64_t*>(e->mData)); return true;
    case AI_FLOAT: out = *static_cast<const float*>(e->mData); return true;
    case AI_DOUBLE: out = *static_cast<const double*>(e->mData); return true;
    default: return false;
    }
}

/// Limits of an imported scene: a scanned body has ~1e5-1e6 vertices; a file
/// with 20 million is not a mannequin. Coordinates beyond 10 km are a wrong
/// unit or a corrupt file. Scene graphs nest a few levels.
constexpr std::size_t kMaxVertices = 20'000'000;
constexpr std::size_t kMaxTriangles = 40'000'000;
constexpr double kMaxCoordinateM = 1e4;
constexpr int kMaxNodeDepth = 1000;
constexpr std::uintmax_t kMaxFileBytes = std::uintmax_t(1) << 30;

struct Collect {
    const aiScene* scene;
    std::vector<ImportedMesh>* out;
    std::map<std::string, int>* name_uses;
    const std::string* path;
    std::size_t* vertices;  ///< vertices collected so far (every instance counts)
    std::size_t* triangles; ///< triangles collected so far
};

Eigen::Matrix4d to_eigen(const aiMatrix4x4& m)
{
    Eigen::Matrix4d e;
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j) e(i, j) = m[static_cast<unsigned>(i)][j];
    return e;
}

// Transforms are chained in double so that the unit scale and axis swap are
// exact (assimp keeps matrices in float).
void visit(const aiNode* node, const Eigen::Matrix4d& parent, const Collect& c, int depth)
{
    if (depth > kMaxNodeDepth)
        throw FileError(*c.path + ": the scene graph is nested deeper than " + std::to_string(kMaxNodeDepth) + " nodes");
    const Eigen::Matrix4d world = parent * to_eigen(node->mTransformation);
    if (!world.allFinite())
        throw FileError(*c.path + ": node '" + node->mName.C_Str() + "' has a transform with a non-finite entry");
    for (unsigned k = 0; k < node->mNumMeshes; ++k) {
        const aiMesh* m = c.scene->mMeshes[node->mMeshes[k]];
        std::string name = m->mName.C_Str();
        if (name.empty()) name = node->mName.C_Str();
        if (name.empty() || name.front() == '<') name = "mesh" + std::to_string(node->mMeshes[k]);
        // A mesh instanced twice, or two meshes sharing a name, stay apart.
        const int use = (*c.name_uses)[name]++;
        if (use > 0) {
            name += '#';
            name += std::to_string(use + 1);
        }

        // Sizes before allocation: a node graph that instances one big mesh
        // many times multiplies it.
        *c.vertices += m->mNumVertices;
        *c.triangles += m->mNumFaces;
        if (*c.vertices > kMaxVertices || *c.triangles > kMaxTriangles)
            throw FileError(*c.path + ": the scene holds more than " + std::to_string(kMaxVertices) + " vertices or " +
                            std::to_string(kMaxTriangles) + " triangles (every instance counted); larger than a body or garment mesh");
        if (m->mNumVertices == 0 || m->mNumFaces == 0)
            throw FileError(*c.path + ": mesh '" + name + "' has no faces (" + std::to_string(m->mNumVertices) +
                            " vertices, " + std::to_string(m->mNumFaces) + " faces)");
        ImportedMesh im;
        im.name = name;
        im.X.resize(m->mNumVertices, 3);
        for (unsigned v = 0; v < m->mNumVertices; ++v) {
            const aiVector3D& p0 = m->mVertices[v];
            if (!std::isfinite(p0.x) || !std::isfinite(p0.y) || !std::isfinite(p0.z))
                throw FileError(*c.path + ": mesh '" + name + "' vertex " + std::to_string(v) +
                                " has a non-finite coordinate (" + format_double(p0.x) + ", " + format_double(p0.y) +
                                ", " + format_double(p0.z) + ")");
            const Eigen::Vector4d p = world * Eigen::Vector4d(p0.x, p0.y, p0.z, 1.0);
            if (!p.head<3>().allFinite() || p.head<3>().cwiseAbs().maxCoeff() > kMaxCoordinateM)
                throw FileError(*c.path + ": mesh '" + name + "' vertex " + std::to_string(v) + " lies at (" + format_value(p.x()) +
                                ", " + format_value(p.y()) + ", " + format_value(p.z()) + ") m, more than " +
                                format_value(kMaxCoordinateM) + " m from the origin (wrong --unit?)");
            im.X.row(v) << p.x(), p.y(), p.z();
        }
        int tris = 0;
        for (unsigned f = 0; f < m->mNumFaces; ++f) tris += m->mFaces[f].mNumIndices == 3;
        if (tris == 0)
            throw FileError(*c.path + ": mesh '" + name + "' has no triangles (only points or lines, " +
                            std::to_string(m->mNumFaces) + " faces)");
        im.F.resize(tris, 3);
        int t = 0;
        for (unsigned f = 0; f < m->mNumFaces; ++f) {
            const aiFace& face = m->mFaces[f];
            if (face.mNumIndices != 3) continue;
            for (int j = 0; j < 3; ++j) {
                if (face.mIndices[j] >= m->mNumVertices)
                    throw FileError(*c.path + ": mesh '" + name + "' face " + std::to_string(f) + " has vertex index " +
                                    std::to_string(face.mIndices[j]) + " >= " + std::to_string(m->mNumVertices));
                im.F(t, j) = static_cast<int>(face.mIndices[j]);
            }
            ++t;
        }
        // A mirroring node transform (negative determinant) flips the winding;
        // flip it back so closed bodies keep outward-facing triangles.
        if (world.topLeftCorner<3, 3>().determinant() < 0) im.F.col(1).swap(im.F.col(2));
        c.out->push_back(std::move(im));
    }
    for (unsigned ch = 0; ch < node->mNumChildren; ++ch) visit(node->mChildren[ch], world, c, depth + 1);
}

AlignedBox box_of(const cloth::Positions& X)
{
    AlignedBox b;
    if (X.rows() == 0) return b;
    b.min = X.colwise().minCoeff().transpose();
    b.max = X.colwise().maxCoeff().transpose();
    return b;
}

void grow(AlignedBox& b, const AlignedBox& o, bool first)
{
    if (first) {
        b = o;
        return;
    }
    b.min = b.min.cwiseMin(o.min);
    b.max = b.max.cwiseMax(o.max);
}

} // namespace

Unit parse_unit(const std::string& text, const std::string& what)
{
    const std::string t = ascii_lower(text);
    if (t == "mm") return Unit::Millimetre;
    if (t == "cm") return Unit::Centimetre;
    if (t == "m") return Unit::Metre;
    if (t == "file" || t == "auto") return Unit::File;
    throw ParameterError(what + ": '" + text + "' is not a unit (mm, cm, m or file)");
}

UpAxis parse_up_axis(const std::string& text, const std::string& what)
{
    const std::string t = ascii_lower(text);
    if (t == "y") return UpAxis::Y;
    if (t == "z") return UpAxis::Z;
    if (t == "file" || t == "auto") return UpAxis::File;
    throw ParameterError(what + ": '" + text + "' is not an up axis (y, z or file)");
}

std::string to_string(Unit u)
{
    switch (u) {
    case Unit::Millimetre: return "mm";
    case Unit::Centimetre: return "cm";
    case Unit::Metre: return "m";
    case Unit::File: break;
    }
    return "file";
}

std::string to_string(UpAxis a)
{
    switch (a) {
    case UpAxis::Y: return "y";
    case UpAxis::Z: return "z";
    case UpAxis::File: break;
    }
    return "file";
}

AlignedBox ImportedMesh::bounds() const { return box_of(X); }

int ImportedScene::vertex_count() const
{
    int n = 0;
    for (const auto& m : meshes) n += m.vertex_count();
    return n;
}

int ImportedScene::triangle_count() const
{
    int n = 0;
    for (const auto& m : meshes) n += m.triangle_count();
    return n;
}

AlignedBox ImportedScene::bounds() const
{
    AlignedBox b;
    for (std::size_t i = 0; i < meshes.size(); ++i) grow(b, meshes[i].bounds(), i == 0);
    return b;
}

const ImportedMesh* ImportedScene::find(const std::string& name) const
{
    for (const auto& m : meshes)
        if (m.name == name) return &m;
    return nullptr;
}

namespace {
ImportedMesh merge_list(const std::vector<const ImportedMesh*>& list, const std::string& name)
{
    ImportedMesh out;
    out.name = name;
    int nv = 0, nf = 0;
    for (const auto* m : list) {
        nv += m->vertex_count();
        nf += m->triangle_count();
    }
    out.X.resize(nv, 3);
    out.F.resize(nf, 3);
    int v0 = 0, f0 = 0;
    for (const auto* m : list) {
        out.X.middleRows(v0, m->vertex_count()) = m->X;
        out.F.middleRows(f0, m->triangle_count()) = m->F.array() + v0;
        v0 += m->vertex_count();
        f0 += m->triangle_count();
    }
    return out;
}
} // namespace

ImportedMesh ImportedScene::merged() const
{
    std::vector<const ImportedMesh*> list;
    for (const auto& m : meshes) list.push_back(&m);
    return merge_list(list, std::filesystem::path(path).stem().string());
}

ImportedMesh ImportedScene::merged(const std::vector<std::string>& names) const
{
    std::vector<const ImportedMesh*> list;
    for (const auto& n : names) {
        const ImportedMesh* m = find(n);
        if (!m) {
            std::string avail;
            for (const auto& mm : meshes) avail += (avail.empty() ? "" : ", ") + mm.name;
            throw ParameterError(path + ": no mesh named '" + n + "' (meshes: " + avail + ")");
        }
        list.push_back(m);
    }
    return merge_list(list, names.size() == 1 ? names.front() : std::filesystem::path(path).stem().string());
}

int weld_vertices(cloth::Positions& X, cloth::Triangles& F)
{
    struct Key {
        double x, y, z;
        bool operator==(const Key& o) const { return x == o.x && y == o.y && z == o.z; }
    };
    struct Hash {
        std::size_t operator()(const Key& k) const
        {
            std::hash<double> h;
            return h(k.x) ^ (h(k.y) * 0x9E3779B97F4A7C15ull) ^ (h(k.z) * 0xC2B2AE3D27D4EB4Full);
        }
    };
    std::unordered_map<Key, int, Hash> seen;
    seen.reserve(static_cast<std::size_t>(X.rows()));
    std::vector<int> remap(static_cast<std::size_t>(X.rows()));
    cloth::Positions Y(X.rows(), 3);
    int n = 0;
    for (int i = 0; i < X.rows(); ++i) {
        // +0.0 so that -0.0 and 0.0 weld.
        Key k{X(i, 0) + 0.0, X(i, 1) + 0.0, X(i, 2) + 0.0};
        auto [it, inserted] = seen.emplace(k, n);
        if (inserted) Y.row(n++) = X.row(i);
        remap[static_cast<std::size_t>(i)] = it->second;
    }
    cloth::Triangles G(F.rows(), 3);
    int m = 0;
    for (int t = 0; t < F.rows(); ++t) {
        const int a = remap[static_cast<std::size_t>(F(t, 0))], b = remap[static_cast<std::size_t>(F(t, 1))],
                  c = remap[static_cast<std::size_t>(F(t, 2))];
        if (a == b || b == c || a == c) continue;
        G.row(m++) << a, b, c;
    }
    const int removed = static_cast<int>(X.rows()) - n;
    X = Y.topRows(n);
    F = G.topRows(m);
    return removed;
}

namespace {

/// The formats a mesh import takes (file extensions), the ones the docs name.
/// assimp reads forty more, but fuzzing found its ASE reader crashing (SEGV)
/// and its OFF reader allocating 16 GB for a header claiming 353,535,235,358
/// vertices (assimp's own test file invalid/OutOfMemory.off) within minutes;
/// the readers of formats nobody drapes are not offered to received files.
const char* const kTakenExtensions[] = {"obj", "dae", "zae", "gltf", "glb", "fbx", "ply", "stl"};
const char* const kTakenFormats = "OBJ, Collada (.dae, .zae), glTF 2 (.gltf, .glb), FBX, PLY and STL";

bool taken(const std::string& ext)
{
    return std::any_of(std::begin(kTakenExtensions), std::end(kTakenExtensions), [&](const char* e) { return ext == e; });
}

/// assimp's line reader (IOStreamBuffer::getNextLine in 5.2): a line ends at
/// '\n', '\r', '\f' or NUL; one terminator is skipped after a line, and a line
/// that starts with a terminator first skips up to and including the next
/// '\n'. The PLY checks read the file the same way so that the header and the
/// rows they look at are the ones assimp parses.
class AssimpLines {
public:
    explicit AssimpLines(std::streambuf* sb) : sb_(sb) {}
    /// The next line (false at the end of the file); throws past max_bytes.
    bool next(std::string& out, std::size_t max_bytes, const std::function<void()>& too_long)
    {
        out.clear();
        int c = sb_->sgetc();
        if (c == kEnd) return false;
        if (is_end(c)) {
            do {
                c = sb_->sbumpc();
                if (c == kEnd) return false;
                ++offset_;
            } while (c != '\n');
            if (sb_->sgetc() == kEnd) return false;
        }
        ++line_;
        while ((c = sb_->sgetc()) != kEnd && !is_end(c)) {
            if (out.size() == max_bytes) too_long();
            out.push_back(static_cast<char>(c));
            sb_->sbumpc();
            ++offset_;
        }
        if (c != kEnd) {
            sb_->sbumpc();
            ++offset_;
        }
        return true;
    }
    std::uintmax_t offset() const { return offset_; } ///< of the next byte
    std::uintmax_t line() const { return line_; }     ///< of the last line read (counted as assimp splits)

private:
    static constexpr int kEnd = std::char_traits<char>::eof();
    static bool is_end(int c) { return c == '\n' || c == '\r' || c == '\f' || c == 0; }
    std::streambuf* sb_;
    std::uintmax_t offset_ = 0, line_ = 0;
};

/// Words separated by spaces and tabs (assimp's SkipSpaces).
std::vector<std::string_view> ply_words(std::string_view line)
{
    std::vector<std::string_view> w;
    std::size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
        const std::size_t b = i;
        while (i < line.size() && line[i] != ' ' && line[i] != '\t') ++i;
        if (i > b) w.push_back(line.substr(b, i - b));
    }
    return w;
}

/// Bytes of a PLY data type (0: not a type assimp reads).
int ply_type_size(std::string_view t)
{
    if (t == "char" || t == "int8" || t == "uchar" || t == "uint8") return 1;
    if (t == "short" || t == "int16" || t == "ushort" || t == "uint16") return 2;
    if (t == "int" || t == "int32" || t == "uint" || t == "uint32" || t == "float" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    return 0;
}

/// A PLY property: a value, or a list (its length's type, then its entries').
struct PlyProperty {
    std::string name;
    int size = 0;       // of a value, or of each list entry
    int count_size = 0; // of a list's length (0: not a list)
    bool count_signed = false, count_float = false;
};

/// A PLY element: its rows and their properties.
struct PlyElement {
    std::string name;
    std::uintmax_t count = 0;
    std::vector<PlyProperty> props;
};

/// What check_ply needs of a PLY header.
struct PlyHeader {
    bool ascii = false, big_endian = false;
    std::vector<PlyElement> elements;
};

constexpr std::size_t kPlyHeadBytes = 64 * 1024;
constexpr std::size_t kPlyRowBytes = 1 << 20;

/// The PLY header up to end_header; nothing when assimp refuses the format line
/// itself (it says why).
template <class Check>
std::optional<PlyHeader> read_ply_header(const std::string& path, AssimpLines& lines, const Check& check_count)
{
    constexpr std::size_t kHeadBytes = kPlyHeadBytes;
    std::string line;
    auto header_too_long = [&] {
        throw FileError(path + ": the PLY header has no end_header line in its first " + std::to_string(kHeadBytes) + " bytes");
    };
    auto at_line = [&] { return path + ": PLY line " + std::to_string(lines.line()) + ": '" + printable(line, 60) + "' "; };
    if (!lines.next(line, kHeadBytes, header_too_long) || line != "ply")
        throw FileError(path + ": a PLY file must start with the line 'ply', not '" + printable(line, 40) + "'");
    if (!lines.next(line, kHeadBytes, header_too_long)) header_too_long();
    const auto format = ply_words(line);
    if (format.size() < 2 || format[0] != "format") return std::nullopt; // assimp refuses it ("Missing format specification")
    PlyHeader h;
    h.ascii = format[1] == "ascii";
    if (!h.ascii && format[1].substr(0, 7) != "binary_") return std::nullopt; // assimp refuses it ("Unknown file format")
    h.big_endian = !h.ascii && format[1].size() > 7 && (format[1][7] == 'b' || format[1][7] == 'B');
    std::vector<PlyElement>& elements = h.elements;
    bool in_element = false; // the previous line was an element or one of its properties
    for (;;) {
        if (lines.offset() > kHeadBytes || !lines.next(line, kHeadBytes, header_too_long)) header_too_long();
        const auto w = ply_words(line);
        if (w.empty()) {
            in_element = false;
            continue;
        }
        const bool keyword = w[0] == "element" || w[0] == "property" || w[0].substr(0, 10) == "end_header";
        if (keyword && (line[0] == ' ' || line[0] == '\t')) throw FileError(at_line() + "starts with spaces: a PLY header keyword starts its line");
        // assimp's TokenMatch: the word, then a space, a tab or the line's end.
        if (w[0] == "end_header") break;
        if (w[0].substr(0, 10) == "end_header")
            throw FileError(at_line() + "is not an end_header line (the word must end the line or be followed by a space)");
        if (w[0] == "element") {
            if (w.size() != 3 || !std::all_of(w[2].begin(), w[2].end(), [](char c) { return c >= '0' && c <= '9'; }))
                throw FileError(at_line() + "is not 'element NAME COUNT'");
            PlyElement e;
            e.name = std::string(w[1]);
            // assimp 5.2 sizes its vertex array by the first vertex element and
            // writes the rows of a second one past its end (a heap overflow
            // ASan caught at a later free: fuzz_mesh).
            if (std::any_of(elements.begin(), elements.end(), [&](const PlyElement& o) { return o.name == e.name; }))
                throw FileError(at_line() + "declares element '" + printable(e.name, 40) + "' a second time");
            const std::string what = "element " + printable(e.name, 40);
            check_count(what, std::string(w[2]), 1, e.name == "face" ? kMaxTriangles : kMaxVertices);
            e.count = static_cast<std::uintmax_t>(std::stod(std::string(w[2])));
            elements.push_back(std::move(e));
            in_element = true;
            continue;
        }
        if (w[0] == "property") {
            if (!in_element) throw FileError(at_line() + "is a property line not directly after its element line (or its other properties)");
            PlyProperty p;
            if (w.size() == 5 && w[1] == "list") {
                p.count_size = ply_type_size(w[2]);
                p.size = ply_type_size(w[3]);
                p.count_signed = w[2] == "char" || w[2] == "int8" || w[2] == "short" || w[2] == "int16" || w[2] == "int" || w[2] == "int32";
                p.count_float = w[2] == "float" || w[2] == "float32" || w[2] == "double" || w[2] == "float64";
                p.name = std::string(w[4]);
            } else if (w.size() == 3) {
                p.size = ply_type_size(w[1]);
                p.name = std::string(w[2]);
            }
            if (p.size == 0 || (w.size() == 5 && p.count_size == 0))
                throw FileError(at_line() + "is not 'property TYPE NAME' or 'property list COUNT_TYPE TYPE NAME' with TYPE one of char, uchar, "
                                            "short, ushort, int, uint, float, double (or int8 ... float64)");
            elements.back().props.push_back(std::move(p));
            continue;
        }
        in_element = false; // comment, obj_info and unknown lines: assimp skips them
    }
    return h;
}

/// ASCII rows: one row a line; the length of a list is a whole number, at most
/// the words left on its line.
void check_ply_ascii_rows(const std::string& path, AssimpLines& lines, const std::vector<PlyElement>& elements)
{
    constexpr std::size_t kRowBytes = kPlyRowBytes;
    std::string line;
    auto at_line = [&] { return path + ": PLY line " + std::to_string(lines.line()) + ": '" + printable(line, 60) + "' "; };
    auto row_too_long = [&] { throw FileError(path + ": PLY line " + std::to_string(lines.line() + 1) + " is longer than " +
                                              std::to_string(kRowBytes) + " bytes: not a row of an ASCII PLY file"); };
    for (const PlyElement& e : elements) {
        for (std::uintmax_t r = 0; r < e.count; ++r) {
            if (!lines.next(line, kRowBytes, row_too_long))
                throw FileError(path + ": the file ends at row " + std::to_string(r) + " of the " + std::to_string(e.count) + " of element '" +
                                printable(e.name, 40) + "' its header declares: a cut file");
            const auto w = ply_words(line);
            std::size_t i = 0;
            for (const PlyProperty& p : e.props) {
                if (i >= w.size()) break;
                if (p.count_size == 0) {
                    ++i;
                    continue;
                }
                const std::string_view n = w[i++];
                const std::size_t left = w.size() - i;
                const bool digits = !n.empty() && n.size() <= 9 && std::all_of(n.begin(), n.end(), [](char c) { return c >= '0' && c <= '9'; });
                if (!digits || std::stoul(std::string(n)) > left)
                    throw FileError(at_line() + "(element '" + printable(e.name, 40) + "' row " + std::to_string(r) + "): the list '" +
                                    printable(p.name, 40) + "' declares '" + printable(n, 20) + "' entries, and the line holds " +
                                    std::to_string(left) + " more values");
                i += std::stoul(std::string(n));
            }
        }
    }
}

/// The length a binary list's row declares: its count's bytes as the header types
/// them (a negative signed count reads as -1).
double ply_list_length(const unsigned char* bytes, const PlyProperty& p, bool big_endian)
{
    unsigned char b[8] = {};
    std::copy(bytes, bytes + p.count_size, b);
    if (big_endian) std::reverse(b, b + p.count_size);
    std::uint64_t raw = 0;
    for (int k = p.count_size; k-- > 0;) raw = raw << 8 | b[k];
    if (p.count_float) {
        if (p.count_size == 4) {
            float f = 0;
            const auto u = static_cast<std::uint32_t>(raw);
            std::memcpy(&f, &u, 4);
            return f;
        }
        double n = 0;
        std::memcpy(&n, &raw, 8);
        return n;
    }
    if (p.count_signed && (raw >> (8 * p.count_size - 1)) & 1) return -1;
    return static_cast<double>(raw);
}

/// Binary rows: they follow the end_header line's terminator byte (at `at`); a
/// list may not declare more entries than the rest of the file holds.
void check_ply_binary_rows(const std::string& path, std::uintmax_t size, std::uintmax_t at, std::streambuf* sb, const PlyHeader& h)
{
    std::array<char, 4096> scratch{};
    auto skip = [&](std::uintmax_t n) {
        while (n > 0) {
            const auto k = static_cast<std::streamsize>(std::min<std::uintmax_t>(n, scratch.size()));
            if (sb->sgetn(scratch.data(), k) != k) return false;
            n -= static_cast<std::uintmax_t>(k);
            at += static_cast<std::uintmax_t>(k);
        }
        return true;
    };
    for (const PlyElement& e : h.elements) {
        std::uintmax_t row_bytes = 0;
        bool lists = false;
        for (const PlyProperty& p : e.props) {
            row_bytes += static_cast<std::uintmax_t>(p.count_size ? p.count_size : p.size);
            lists = lists || p.count_size;
        }
        auto cut = [&](std::uintmax_t r) {
            throw FileError(path + ": the file ends inside row " + std::to_string(r) + " of the " + std::to_string(e.count) + " of element '" +
                            printable(e.name, 40) + "' its header declares (byte " + std::to_string(at) + " of " + std::to_string(size) +
                            "): a cut or corrupt file");
        };
        if (!lists) {
            if (row_bytes * e.count > size - at)
                throw FileError(path + ": element '" + printable(e.name, 40) + "' declares " + std::to_string(e.count) + " rows of " +
                                std::to_string(row_bytes) + " bytes from byte " + std::to_string(at) + ", more than the file's " +
                                std::to_string(size) + " bytes: a cut or corrupt file");
            if (!skip(row_bytes * e.count)) cut(0);
            continue;
        }
        for (std::uintmax_t r = 0; r < e.count; ++r) {
            for (const PlyProperty& p : e.props) {
                if (p.count_size == 0) {
                    if (!skip(static_cast<std::uintmax_t>(p.size))) cut(r);
                    continue;
                }
                unsigned char b[8] = {};
                if (sb->sgetn(reinterpret_cast<char*>(b), p.count_size) != p.count_size) cut(r);
                at += static_cast<std::uintmax_t>(p.count_size);
                const double n = ply_list_length(b, p, h.big_endian);
                const double fits = static_cast<double>(size - at) / p.size;
                if (!(n >= 0 && n == std::floor(n) && n <= fits))
                    throw FileError(path + ": element '" + printable(e.name, 40) + "' row " + std::to_string(r) + " (byte " +
                                    std::to_string(at - static_cast<std::uintmax_t>(p.count_size)) + "): the list '" + printable(p.name, 40) +
                                    "' declares " + format_value(n) + " entries, more than the rest of the file holds: a corrupt file");
                if (!skip(static_cast<std::uintmax_t>(n) * static_cast<std::uintmax_t>(p.size))) cut(r);
            }
        }
    }
}

/// A PLY file checked the way assimp reads it (fuzz_mesh's findings): the
/// first line "ply" (NUL bytes after the word made assimp's reader loop
/// forever); an end_header line within the first 64 KiB as assimp recognises
/// it (a damaged one, or the word followed by a vertical tab, and assimp reads
/// past the end of the file looking for it, forever); element counts that fit
/// the file and the scene limits; property lines assimp can read, directly
/// after their element; and in the rows, every list's length: assimp sizes
/// the list by the number it reads before looking at the entries (an ASCII row
/// "4444444444...4 7 6 5 4" made it ask for 3.8 GB), so a list must not claim
/// more entries than its row (ASCII) or the rest of the file (binary) holds.
template <class Check>
void check_ply(const std::string& path, std::uintmax_t size, const Check& check_count)
{
    std::ifstream in(path, std::ios::binary);
    AssimpLines lines(in.rdbuf());
    const auto h = read_ply_header(path, lines, check_count);
    if (!h) return;
    if (h->ascii) check_ply_ascii_rows(path, lines, h->elements);
    else check_ply_binary_rows(path, size, lines.offset(), in.rdbuf(), *h);
}

/// A PLY header checked before assimp reads the file (fuzz_mesh's findings):
/// the first line "ply" (NUL bytes after the word made assimp's reader loop
/// forever), an "end_header" line within the first 64 KiB (a damaged one did
/// the same), and element counts that fit the file (at least one byte per
/// element) and the scene limits.
void check_header(const std::string& path, const std::string& ext, std::uintmax_t size)
{
    constexpr std::size_t kHeadBytes = 64 * 1024;
    std::ifstream in(path, std::ios::binary);
    std::string head(kHeadBytes, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    auto check = [&](const std::string& what, const std::string& text, double bytes_each, std::size_t limit) {
        double n = 0;
        if (!parse_number(text, n) || n < 0 || n != std::floor(n))
            throw FileError(path + ": the header's " + what + " '" + printable(text, 40) + "' is not a count");
        if (n * bytes_each > static_cast<double>(size) || n > static_cast<double>(limit))
            throw FileError(path + ": the header declares " + what + " = " + text + ", more than the file's " + std::to_string(size) +
                            " bytes can hold (or the " + std::to_string(limit) + " a mesh import takes): a corrupt header");
    };
    // Binary glTF: the lengths its header declares must fit the file (a
    // 3 KB .glb declaring a 4 GiB JSON chunk made assimp allocate 4 GiB).
    if (ext == "glb" || head.compare(0, 4, "glTF") == 0) {
        auto le32 = [&](std::size_t i) -> std::uint64_t {
            if (i + 4 > head.size()) return 0;
            return static_cast<std::uint64_t>(static_cast<unsigned char>(head[i])) |
                   static_cast<std::uint64_t>(static_cast<unsigned char>(head[i + 1])) << 8 |
                   static_cast<std::uint64_t>(static_cast<unsigned char>(head[i + 2])) << 16 |
                   static_cast<std::uint64_t>(static_cast<unsigned char>(head[i + 3])) << 24;
        };
        if (head.size() >= 20 && head.compare(0, 4, "glTF") == 0) {
            const std::uint64_t total = le32(8), chunk = le32(12);
            if (total > size || 20 + chunk > size)
                throw FileError(path + ": the binary glTF header declares " + std::to_string(total) + " bytes and a first chunk of " +
                                std::to_string(chunk) + " bytes, more than the file's " + std::to_string(size) + ": a corrupt or cut file");
        }
    }
    // A PLY file by its name or by its content (assimp recognises the word
    // "ply" at the start whatever follows it, NUL bytes included).
    std::size_t first = 0;
    while (first < head.size() && std::isspace(static_cast<unsigned char>(head[first]))) ++first;
    const bool ply = ext == "ply" || ascii_lower(head.substr(first, 3)) == "ply";
    if (ply) check_ply(path, size, check);
}

/// Text formats are UTF-8 text without control characters besides tab, line
/// feed and carriage return (XML 1.0 and JSON forbid them; OBJ is lines of
/// text). Bytes that are neither in a Collada index list made assimp allocate
/// 12 GB (a 0x1F run, then a lone 0xB3: fuzz_mesh); a UTF-16 file is refused
/// with the same message (save it as UTF-8).
void check_text(const std::string& path, const std::string& ext)
{
    if (ext != "dae" && ext != "gltf" && ext != "obj") return;
    std::ifstream in(path, std::ios::binary);
    std::string buf(1 << 16, '\0');
    std::string carry; // an incomplete UTF-8 sequence at the end of the previous block
    std::uintmax_t offset = 0;
    auto fail = [&](std::uintmax_t at, const std::string& what) {
        throw FileError(path + ": byte " + std::to_string(at) + " " + what + ", which a ." + ext +
                        " file (UTF-8 text) cannot hold: a damaged file, or one saved in another encoding");
    };
    while (in) {
        in.read(buf.data(), static_cast<std::streamsize>(buf.size()));
        const auto n = static_cast<std::size_t>(in.gcount());
        for (std::size_t i = 0; i < n; ++i) {
            const auto c = static_cast<unsigned char>(buf[i]);
            if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7f)
                fail(offset + i, "is a control character (" + printable(std::string(1, buf[i])) + ")");
        }
        std::string block = carry + buf.substr(0, n);
        // Keep an incomplete sequence at the end for the next block.
        std::size_t cut = block.size();
        for (std::size_t k = 1; k <= 3 && k <= block.size(); ++k) {
            const auto b = static_cast<unsigned char>(block[block.size() - k]);
            if ((b & 0xC0) == 0xC0) { // a lead byte: is its sequence complete?
                const std::size_t len = b >= 0xF0 ? 4 : b >= 0xE0 ? 3 : 2;
                if (k < len && n == buf.size()) cut = block.size() - k;
                break;
            }
            if ((b & 0x80) == 0) break;
        }
        if (const std::size_t bad = first_invalid_utf8(std::string_view(block).substr(0, cut)); bad != std::string_view::npos) {
            std::string what = printable(block.substr(bad, 1)); // appended, not concatenated: GCC 12's -Wrestrict false positive
            what += " is not UTF-8 text";
            fail(offset - carry.size() + bad, what);
        }
        carry = block.substr(cut);
        offset += n;
    }
}

/// The value of attribute `key` in a start tag's text ("" when absent).
std::string text_attribute(const std::string& tag, const std::string& key)
{
    for (std::size_t pos = tag.find(key); pos != std::string::npos; pos = tag.find(key, pos + 1)) {
        if (pos > 0 && !std::isspace(static_cast<unsigned char>(tag[pos - 1]))) continue;
        std::size_t i = pos + key.size();
        while (i < tag.size() && std::isspace(static_cast<unsigned char>(tag[i]))) ++i;
        if (i >= tag.size() || tag[i] != '=') continue;
        ++i;
        while (i < tag.size() && std::isspace(static_cast<unsigned char>(tag[i]))) ++i;
        if (i >= tag.size() || (tag[i] != '"' && tag[i] != '\'')) continue;
        const char q = tag[i];
        const std::size_t end = tag.find(q, i + 1);
        if (end == std::string::npos) return {};
        return tag.substr(i + 1, end - i - 1);
    }
    return {};
}

/// A whole-number attribute (at most 12 digits); nullopt when absent or not one.
std::optional<std::uintmax_t> whole_attribute(const std::string& tag, const std::string& key)
{
    const std::string v = text_attribute(tag, key);
    if (v.empty() || v.size() > 12 || !std::all_of(v.begin(), v.end(), [](char ch) { return ch >= '0' && ch <= '9'; }))
        return std::nullopt;
    return std::stoull(v);
}

/// Collada index lists (<p>) hold whole numbers separated by white space.
/// assimp's reader loops over a <p> until its end, reading a number and then
/// skipping spaces; a character that is neither (a run of '^' in a polylist:
/// fuzz_mesh) moves it nowhere, and it appends index 0 until memory runs out
/// (a 5 KB file, 2 GiB in one allocation). Checked in one pass over the file:
/// comments, CDATA sections, processing instructions and declarations are
/// skipped; inside <p> only digits, signs, spaces, tabs and line ends are
/// taken, up to its end tag.
/// check_collada_indices' one pass over a Collada file: its reader (lines counted,
/// tags and values read without building a document) and what the checks keep
/// between elements.
class ColladaScan {
public:
    static constexpr int kEnd = std::char_traits<char>::eof();
    ColladaScan(const std::string& path, std::streambuf* sb) : path_(path), sb_(sb) {}

    /// Scans to the end of the file; throws FileError at the first damage.
    void run()
    {
        for (int c = next(); c != kEnd; c = next()) {
            if (c != '<') continue;
            c = next();
            if (c == '!' || c == '?') {
                if (!skip_markup(c)) return;
                continue;
            }
            if (!element(c)) return;
        }
    }

private:
    /// The rest of a start tag (quoted values may hold '>'); the text kept for
    /// attributes is capped at 4 KiB; `self_closing`: it ends in "/>".
    struct Tag {
        std::string text;
        bool self_closing = false;
    };
    /// The values of an element's text up to the next tag: how many (separated by
    /// white space) and the sum of those that are whole numbers.
    struct Values {
        std::uintmax_t count = 0, sum = 0;
    };
    /// The <vertex_weights> we are in (line 0: none).
    struct Weights {
        std::uintmax_t line = 0, count = 0, inputs = 0, vcount_values = 0, vcount_sum = 0, v_values = 0;
    };

    static bool is_space(int c) { return c == ' ' || c == '\t' || c == '\r' || c == '\n'; }
    static bool is_array(const std::string& n)
    {
        return n == "float_array" || n == "int_array" || n == "Name_array" || n == "bool_array" || n == "IDREF_array";
    }

    int next()
    {
        const int c = sb_->sbumpc();
        if (c == '\n') ++line_;
        return c;
    }
    /// Consumes up to and including `end`; false at the end of the file.
    bool skip_past(std::string_view end)
    {
        std::string last;
        for (int c; (c = next()) != kEnd;) {
            last.push_back(static_cast<char>(c));
            if (last.size() > end.size()) last.erase(0, 1);
            if (last == end) return true;
        }
        return false;
    }
    /// The rest of a start tag from `c` up to its '>'; `c` is left on the '>'
    /// (kEnd at the end of the file).
    Tag read_tag(int& c)
    {
        Tag t;
        int quote = 0, before = 0;
        while (c != kEnd && (quote || c != '>')) {
            if (quote && c == quote) quote = 0;
            else if (!quote && (c == '"' || c == '\'')) quote = c;
            if (t.text.size() < 4096) t.text.push_back(static_cast<char>(c));
            before = c;
            c = next();
        }
        t.self_closing = before == '/';
        return t;
    }
    Values read_values(int& c)
    {
        Values v;
        std::uintmax_t current = 0;
        bool in_value = false;
        for (c = next(); c != kEnd && c != '<'; c = next()) {
            if (is_space(c)) {
                if (in_value) v.sum += current;
                in_value = false;
                current = 0;
            } else {
                if (!in_value) ++v.count;
                in_value = true;
                current = (c >= '0' && c <= '9' && current < (std::uintmax_t(1) << 40)) ? current * 10 + std::uintmax_t(c - '0') : current;
            }
        }
        if (in_value) v.sum += current;
        return v;
    }
    /// Comments, CDATA sections, declarations (after "<!") and processing
    /// instructions (after "<?"); false at the end of the file.
    bool skip_markup(int c)
    {
        if (c == '?') return skip_past("?>");
        c = next();
        if (c == '-' && next() == '-') return skip_past("-->");
        if (c == '[') return skip_past("]]>");
        return c == '>' || skip_past(">");
    }
    /// One element from its name's first character; false at the end of the file.
    bool element(int c)
    {
        // The element's name: <p>, and <polylist> with its <vcount> (a polylist
        // without one before its <p>: assimp read the count of each polygon
        // from an empty list, a null pointer, and `drape import` died of SIGSEGV).
        const bool closing = c == '/';
        if (closing) c = next();
        std::string name;
        while (c != kEnd && !is_space(c) && c != '>' && c != '/' && name.size() < 16) {
            name.push_back(static_cast<char>(c));
            c = next();
        }
        if (closing) {
            close(name);
            return true;
        }
        if (weights_.line && (name == "input" || name == "vcount" || name == "v")) return weights_child(name, c);
        if (name == "polylist") {
            polylist_ = line_;
            vcount_ = false;
            return true;
        }
        if (name == "vertex_weights") {
            const Tag tag = read_tag(c);
            if (c == kEnd) return false;
            if (tag.self_closing) return true;
            weights_ = {};
            weights_.line = line_;
            weights_.count = whole_attribute(tag.text, "count").value_or(0);
            return true;
        }
        if (name == "vcount") vcount_ = true;
        if (is_array(name) || name == "accessor") return array_or_accessor(name, c);
        if (name != "p") return true;
        return index_list(c);
    }
    void close(const std::string& name)
    {
        if (name == "polylist") polylist_ = 0;
        if (name != "vertex_weights" || !weights_.line) return;
        // Skin weights: one <vcount> value per vertex, and in <v> as many (joint,
        // weight) groups as the <vcount> values add up to. Counts that disagree
        // made assimp 5.2 read past its lists (SIGSEGV, fuzz_mesh).
        const std::string at = path_ + ": line " + std::to_string(weights_.line) + ": <vertex_weights count=\"" +
                               std::to_string(weights_.count) + "\">";
        if (weights_.vcount_values != weights_.count)
            throw FileError(at + " has " + std::to_string(weights_.vcount_values) + " values in its <vcount> (one per vertex expected; a damaged file)");
        if (weights_.v_values != weights_.vcount_sum * std::max<std::uintmax_t>(weights_.inputs, 1))
            throw FileError(at + " has " + std::to_string(weights_.v_values) + " values in its <v>, not " + std::to_string(weights_.vcount_sum) +
                            " x " + std::to_string(weights_.inputs) + " (the <vcount> values times the inputs; a damaged file)");
        weights_ = {};
    }
    bool weights_child(const std::string& name, int c)
    {
        if (name == "input") {
            ++weights_.inputs;
            return true;
        }
        read_tag(c);
        if (c == kEnd) return false;
        // The values up to the end tag (whole numbers; others are the <p> check's kind of damage).
        const Values v = read_values(c);
        if (name == "vcount") {
            weights_.vcount_values = v.count;
            weights_.vcount_sum = v.sum;
        } else {
            weights_.v_values = v.count;
        }
        return true;
    }
    /// Value arrays: <float_array count="N"> etc. must hold N values (a count of 0
    /// before 24 values: assimp 5.2 kept an empty array, an accessor read it
    /// through a null pointer and `drape import` died of SIGSEGV), and every
    /// <accessor> must read inside the array it names.
    bool array_or_accessor(const std::string& name, int c)
    {
        const Tag t = read_tag(c);
        const std::string& tag = t.text;
        if (c == kEnd) return false;
        const std::uintmax_t at = line_;
        const auto count = whole_attribute(tag, "count");
        if (name == "accessor") {
            // An accessor reads `count` groups of `stride` values from its array,
            // starting at `offset`: they must be in the array.
            std::string src = text_attribute(tag, "source");
            if (!src.empty() && src[0] == '#') src.erase(0, 1);
            const auto it = arrays_.find(src);
            const auto stride = whole_attribute(tag, "stride").value_or(1), offset = whole_attribute(tag, "offset").value_or(0);
            if (count && it != arrays_.end() && offset + *count * std::max<std::uintmax_t>(stride, 1) > it->second)
                throw FileError(path_ + ": line " + std::to_string(at) + ": an <accessor> reads " + std::to_string(*count) + " x " +
                                std::to_string(stride) + " values from offset " + std::to_string(offset) + " of '" + printable(src, 60) +
                                "', which holds " + std::to_string(it->second) + " (a damaged file)");
            return true;
        }
        if (tag.empty() || t.self_closing) return true; // <float_array> without attributes, <float_array/>
        // The values up to the end tag: as many as the count says.
        const std::uintmax_t values = read_values(c).count;
        if (!count || *count != values)
            throw FileError(path_ + ": line " + std::to_string(at) + ": <" + name + "> declares count " +
                            (count ? std::to_string(*count) : std::string("(none)")) + " but holds " + std::to_string(values) +
                            " values (a damaged file)");
        if (const std::string id = text_attribute(tag, "id"); !id.empty()) arrays_[id] = values;
        return true;
    }
    /// An index list <p>: whole numbers separated by white space up to its end tag.
    bool index_list(int c)
    {
        if (polylist_ && !vcount_)
            throw FileError(path_ + ": line " + std::to_string(line_) + ": the <polylist> opened on line " + std::to_string(polylist_) +
                            " has an index list <p> but no <vcount> before it (the number of corners of each polygon)");
        const bool empty = read_tag(c).self_closing;
        if (c == kEnd) return false;
        if (empty) return true; // <p/>
        const std::uintmax_t start = line_;
        for (c = next(); c != kEnd; c = next()) {
            if ((c >= '0' && c <= '9') || c == '+' || c == '-' || is_space(c)) continue;
            if (c == '<' && sb_->sgetc() == '/') return true;
            std::string word(1, static_cast<char>(c));
            for (int d = sb_->sgetc(); d != kEnd && !is_space(d) && d != '<' && word.size() < 20; d = sb_->sgetc())
                word.push_back(static_cast<char>(sb_->sbumpc()));
            throw FileError(path_ + ": line " + std::to_string(line_) + ": the index list <p> (opened on line " + std::to_string(start) +
                            ") holds '" + printable(word, 20) +
                            "', not a whole number: Collada indices are whole numbers separated by spaces (a damaged file)");
        }
        return false;
    }

    const std::string& path_;
    std::streambuf* sb_;
    std::uintmax_t line_ = 1;
    std::map<std::string, std::uintmax_t> arrays_;
    Weights weights_;
    std::uintmax_t polylist_ = 0; ///< the line of the <polylist> we are in (0: none)
    bool vcount_ = false;         ///< that polylist had its <vcount>
};

void check_collada_indices(const std::string& path, const std::string& ext)
{
    if (ext != "dae") return;
    std::ifstream in(path, std::ios::binary);
    ColladaScan(path, in.rdbuf()).run();
}

} // namespace

ImportedScene import_scene(const std::string& path, const ImportOptions& opt)
{
    namespace fs = std::filesystem;
    std::error_code ec;
    if (!fs::is_regular_file(path, ec)) throw FileError(path + ": no such file");
    const auto size = fs::file_size(path, ec);
    if (ec) throw FileError(path + ": cannot read the file size (" + ec.message() + ")");
    if (size == 0) throw FileError(path + ": the file is empty");
    if (size > kMaxFileBytes)
        throw FileError(path + ": the file is " + std::to_string(size) + " bytes, more than the " + std::to_string(kMaxFileBytes) +
                        " a mesh import reads");
    {
        std::ifstream probe(path, std::ios::binary);
        if (!probe) throw FileError(path + ": cannot open the file for reading");
    }
    std::string ext = ascii_lower(fs::path(path).extension().string());
    if (!ext.empty()) ext.erase(0, 1);
    if (!taken(ext))
        throw FileError(path + ": '." + printable(ext, 20) + "' is not a mesh format this import takes (" + kTakenFormats + ")");
    check_header(path, ext, size);
    check_text(path, ext);
    check_collada_indices(path, ext);

    Assimp::Importer importer;
    // Only the readers of the formats taken: a file is never handed to another
    // reader by its content either.
    for (std::size_t i = importer.GetImporterCount(); i-- > 0;) {
        const aiImporterDesc* d = importer.GetImporterInfo(i);
        std::istringstream exts(d && d->mFileExtensions ? d->mFileExtensions : "");
        bool keep = false;
        for (std::string e; exts >> e;) keep = keep || taken(ascii_lower(e));
        if (keep) continue;
        Assimp::BaseImporter* reader = importer.GetImporter(i);
        if (importer.UnregisterLoader(reader) == AI_SUCCESS) delete reader; // unregistering hands it back
    }
    // An explicit up axis describes the file's own numbers, so assimp must not
    // rotate Collada's Z_UP into Y_UP first.
    if (opt.up != UpAxis::File) importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
    const unsigned flags = aiProcess_Triangulate | aiProcess_ValidateDataStructure;
    const aiScene* scene = importer.ReadFile(path, flags);
    if (!scene) {
        std::string why = importer.GetErrorString();
        if (why.find("No suitable reader") != std::string::npos)
            throw FileError(path + ": not a mesh format assimp can read (" + why + ")");
        throw FileError(path + ": cannot import (" + (why.empty() ? std::string("unknown assimp error") : why) + ")");
    }
    if (scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE)
        throw FileError(path + ": the scene is incomplete (truncated file or one without geometry)");
    if (!scene->mRootNode || scene->mNumMeshes == 0) throw FileError(path + ": the file holds no mesh");

    ImportedScene out;
    out.path = path;
    aiString fmt;
    if (meta_get(scene, "SourceAsset_Format", fmt)) out.format = fmt.C_Str();
    const std::string f = ascii_lower(out.format);
    const bool is_fbx = f.find("fbx") != std::string::npos;
    const bool is_collada = f.find("collada") != std::string::npos;
    const bool is_gltf = f.find("gltf") != std::string::npos;

    // --- unit ---
    aiMatrix4x4 root = scene->mRootNode->mTransformation;
    if (opt.unit != Unit::File) {
        out.unit_scale = unit_metres(opt.unit);
        out.unit_source = "option";
        if (is_collada) {
            // assimp always multiplies Collada's root by <unit meter="...">;
            // an explicit unit replaces it, so take that uniform scale out again.
            aiMatrix3x3 r(root);
            const double det = r.Determinant();
            if (std::abs(det) > 0) {
                const float s = static_cast<float>(std::cbrt(std::abs(det)));
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j) root[i][j] /= s;
            }
        }
    } else if (is_fbx) {
        double cm_per_unit = 0;
        if (meta_number(scene, "UnitScaleFactor", cm_per_unit) && cm_per_unit > 0) {
            out.unit_scale = cm_per_unit * 0.01;
            out.unit_source = "file";
        } else {
            out.unit_scale = 0.01; // FBX's own default unit is the centimetre
            out.unit_source = "assumed";
        }
    } else if (is_collada || is_gltf) {
        out.unit_scale = 1.0; // Collada: assimp applied <unit>; glTF: metres by specification
        out.unit_source = "file";
    } else {
        out.unit_scale = 1.0;
        out.unit_source = "assumed";
    }

    // --- up axis ---
    if (opt.up != UpAxis::File) {
        out.up = opt.up;
        out.up_source = "option";
    } else if (is_fbx) {
        double axis = 1, sign = 1;
        const bool has_axis = meta_number(scene, "UpAxis", axis);
        meta_number(scene, "UpAxisSign", sign);
        if (has_axis && sign > 0 && (axis == 1 || axis == 2)) {
            out.up = axis == 2 ? UpAxis::Z : UpAxis::Y;
            out.up_source = "file";
        } else {
            out.up = UpAxis::Y;
            out.up_source = "assumed";
        }
    } else if (is_collada || is_gltf) {
        out.up = UpAxis::Y; // assimp turns Collada's <up_axis> into y up; glTF is y up
        out.up_source = "file";
    } else {
        out.up = UpAxis::Y;
        out.up_source = "assumed";
    }

    // Engine frame: metres, z up. From y up: (x, y, z) -> (x, -z, y), a proper
    // rotation about x by +90 degrees, so handedness and winding are kept.
    Eigen::Matrix4d to_engine = Eigen::Matrix4d::Identity();
    const double s = out.unit_scale;
    if (out.up == UpAxis::Y) {
        to_engine.topLeftCorner<3, 3>() << s, 0, 0, 0, 0, -s, 0, s, 0;
    } else {
        to_engine.topLeftCorner<3, 3>() = s * Eigen::Matrix3d::Identity();
    }

    std::map<std::string, int> uses;
    std::size_t vertices = 0, triangles = 0;
    Collect c{scene, &out.meshes, &uses, &path, &vertices, &triangles};
    const Eigen::Matrix4d base = to_engine * to_eigen(root);
    // visit() multiplies by the node's own transform; the root's was adjusted above.
    aiNode* rn = scene->mRootNode;
    const aiMatrix4x4 keep = rn->mTransformation;
    rn->mTransformation = aiMatrix4x4();
    try {
        visit(rn, base, c, 0);
    } catch (...) {
        rn->mTransformation = keep;
        throw;
    }
    rn->mTransformation = keep;
    if (out.meshes.empty()) throw FileError(path + ": no node of the scene references a mesh");

    if (opt.weld)
        for (auto& m : out.meshes) weld_vertices(m.X, m.F);
    for (auto& m : out.meshes)
        if (m.F.rows() == 0) throw FileError(path + ": mesh '" + m.name + "' has only degenerate triangles");
    return out;
}

} // namespace drape::importers
