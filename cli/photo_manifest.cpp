#include "cli/photo_manifest.hpp"

#include "engine/core/error.hpp"
#include "engine/core/io.hpp"
#include "engine/core/text.hpp"
#include "engine/core/units.hpp"

#include <algorithm>
#include <filesystem>
#include <map>
#include <sstream>

namespace drape::cli {

// Helpers in a named namespace: the CLI is compiled in unity batches.
namespace manifest_detail {

/// Largest manifest read [bytes]: a row per photo is a few dozen bytes.
constexpr std::size_t kMaxManifestBytes = std::size_t(16) << 20;

/// One CSV line into cells: commas separate, a quoted cell may hold commas and
/// doubled quotes. Blanks around a cell are dropped.
std::vector<std::string> split_cells(const std::string& line, const std::string& where)
{
    std::vector<std::string> out;
    std::string cell;
    bool quoted = false, was_quoted = false;
    for (std::size_t i = 0; i < line.size(); ++i) {
        const char c = line[i];
        if (quoted) {
            if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
                cell += '"';
                ++i;
            } else if (c == '"') {
                quoted = false;
            } else {
                cell += c;
            }
        } else if (c == '"' && trim_blanks(cell).empty() && !was_quoted) {
            quoted = was_quoted = true;
            cell.clear();
        } else if (c == ',') {
            out.push_back(was_quoted ? cell : trim_blanks(cell));
            cell.clear();
            was_quoted = false;
        } else if (!was_quoted || (c != ' ' && c != '\t')) {
            if (was_quoted) throw FileError(where + ": text after a quoted cell in '" + printable(line) + "'");
            cell += c;
        }
    }
    if (quoted) throw FileError(where + ": a quote is not closed in '" + printable(line) + "' (a cell cannot span lines)");
    out.push_back(was_quoted ? cell : trim_blanks(cell));
    return out;
}

} // namespace manifest_detail

const std::vector<std::string>& manifest_columns()
{
    static const std::vector<std::string> cols = {"photo", "disc_mm", "specimen_mm", "specimen_angle_deg", "centre_x_px", "centre_y_px"};
    return cols;
}

const ManifestRow* PhotoManifest::find(const std::string& photo) const
{
    for (const auto& r : rows)
        if (r.photo == photo) return &r;
    return nullptr;
}

std::string PhotoManifest::where(const ManifestRow& r) const { return file + ":" + std::to_string(r.line); }

PhotoManifest read_photo_manifest(const std::string& path, const std::string& folder, const std::vector<std::string>& photos)
{
    using namespace manifest_detail;
    namespace fs = std::filesystem;
    PhotoManifest m;
    m.file = path;
    std::error_code ec;
    if (!fs::is_regular_file(fs::path(path), ec)) throw FileError(path + ": no such manifest file (--manifest)");
    std::string text = read_file(path, kMaxManifestBytes);
    if (text.rfind("\xEF\xBB\xBF", 0) == 0) text.erase(0, 3); // a spreadsheet's UTF-8 byte-order mark
    if (!is_valid_utf8(text)) throw FileError(path + ": not UTF-8 text (a manifest is a CSV file)");
    std::istringstream in(text);
    std::string line;
    int line_no = 0;
    // The header: the first line that is not blank.
    while (std::getline(in, line)) {
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (!trim_blanks(line).empty()) break;
        line.clear();
    }
    if (trim_blanks(line).empty())
        throw FileError(path + ": empty manifest (expected a header line such as photo,disc_mm,specimen_mm)");
    const std::string header_where = path + ":" + std::to_string(line_no);
    m.columns = split_cells(line, header_where);
    const auto& known = manifest_columns();
    std::string known_list;
    for (const auto& k : known) known_list += (known_list.empty() ? "" : ", ") + k;
    std::map<std::string, std::size_t> col;
    for (std::size_t i = 0; i < m.columns.size(); ++i) {
        const std::string& c = m.columns[i];
        if (std::find(known.begin(), known.end(), c) == known.end())
            throw FileError(header_where + ": column " + std::to_string(i + 1) + " '" + printable(c) + "' is not a manifest column (known: " +
                            known_list + ")");
        if (col.count(c)) throw FileError(header_where + ": column '" + c + "' appears twice in the header");
        col[c] = i;
    }
    if (!col.count("photo")) throw FileError(header_where + ": no 'photo' column in the header '" + printable(line) + "'");
    if (col.count("centre_x_px") != col.count("centre_y_px"))
        throw FileError(header_where + ": column '" + std::string(col.count("centre_x_px") ? "centre_x_px" : "centre_y_px") +
                        "' without '" + (col.count("centre_x_px") ? "centre_y_px" : "centre_x_px") + "' (the disc centre takes both)");

    std::map<std::string, int> seen;
    while (std::getline(in, line)) {
        ++line_no;
        if (!line.empty() && line.back() == '\r') line.pop_back();
        if (trim_blanks(line).empty()) continue;
        const std::string where = path + ":" + std::to_string(line_no);
        const auto cells = split_cells(line, where);
        if (cells.size() > m.columns.size())
            throw FileError(where + ": " + std::to_string(cells.size()) + " cells, the header has " + std::to_string(m.columns.size()) + " columns ('" +
                            printable(line) + "')");
        // A short row: the missing cells at its end are empty.
        auto cell = [&](const std::string& name) -> std::string {
            const auto it = col.find(name);
            if (it == col.end() || it->second >= cells.size()) return {};
            return cells[it->second];
        };
        auto bad = [&](const std::string& name, const std::string& value, const std::string& why) {
            return FileError(where + ": column '" + name + "': '" + printable(value) + "' " + why);
        };
        auto number = [&](const std::string& name, double lo, double hi, const std::string& unit) -> std::optional<double> {
            const std::string v = cell(name);
            if (v.empty()) return std::nullopt;
            double x = 0;
            if (!parse_number(v, x)) throw bad(name, v, "is not a number");
            if (!(x >= lo && x <= hi))
                throw bad(name, v, "is outside [" + format_value(lo) + ", " + format_value(hi) + "]" + (unit.empty() ? "" : " " + unit));
            return x;
        };
        ManifestRow r;
        r.line = line_no;
        r.photo = cell("photo");
        if (r.photo.empty()) throw bad("photo", r.photo, "is empty: every row names a photo of the folder");
        if (r.photo.find('/') != std::string::npos || r.photo.find('\\') != std::string::npos || r.photo == "." || r.photo == "..")
            throw bad("photo", r.photo, "is not a file name: the photos are named as they are inside " + printable(folder));
        if (std::find(photos.begin(), photos.end(), r.photo) == photos.end()) {
            if (fs::exists(fs::path(folder) / r.photo, ec))
                throw bad("photo", r.photo, "is in " + printable(folder) + " but is not a photo the batch measures (.jpg, .jpeg, .png, .tif, .bmp)");
            throw bad("photo", r.photo, "does not exist in " + printable(folder));
        }
        if (const auto it = seen.find(r.photo); it != seen.end())
            throw bad("photo", r.photo, "is listed twice (lines " + std::to_string(it->second) + " and " + std::to_string(line_no) + ")");
        seen[r.photo] = line_no;
        r.disc_mm = number("disc_mm", 1, 10000, "mm");
        if (const std::string v = cell("specimen_mm"); !v.empty()) {
            const auto x = v.find_first_of("xX");
            double w = 0, l = 0;
            const bool ok = x == std::string::npos ? parse_number(v, w) : parse_number(v.substr(0, x), w) && parse_number(v.substr(x + 1), l);
            if (!ok) throw bad("specimen_mm", v, "is not a diameter (300) or width x length (300x400) in mm");
            if (!(w >= 1 && w <= 10000) || (x != std::string::npos && !(l >= 1 && l <= 10000)))
                throw bad("specimen_mm", v, "is outside [1, 10000] mm");
            r.specimen_width_mm = w;
            if (x != std::string::npos) r.specimen_length_mm = l;
        }
        if (const std::string v = cell("specimen_angle_deg"); !v.empty()) {
            r.specimen_angle_text = v;
            if (v == "auto") r.specimen_angle_auto = true;
            else r.specimen_angle_deg = number("specimen_angle_deg", -360, 360, "deg");
        }
        r.centre_x_px = number("centre_x_px", 0, 20000, "px");
        r.centre_y_px = number("centre_y_px", 0, 20000, "px");
        if (r.centre_x_px.has_value() != r.centre_y_px.has_value()) {
            const std::string given = r.centre_x_px ? "centre_x_px" : "centre_y_px", empty = r.centre_x_px ? "centre_y_px" : "centre_x_px";
            throw bad(empty, "", "is empty but '" + given + "' is given: the disc centre takes both");
        }
        m.rows.push_back(r);
    }
    return m;
}

} // namespace drape::cli
