#include "engine/core/json_reader.hpp"

#include "engine/core/error.hpp"
#include "engine/core/units.hpp"

#include <cmath>
#include <sstream>

namespace drape {

using nlohmann::json;

std::string describe_json(const json& v)
{
    std::string s = v.dump(-1, ' ', false, json::error_handler_t::replace);
    if (s.size() > 60) s = s.substr(0, 57) + "...";
    return std::string(v.type_name()) + " " + s;
}

void JsonReader::fail(const std::string& field, const std::string& what) const
{
    throw FileError(m_where + ": field '" + field + "' " + what);
}

const json* JsonReader::find(const json& root, const std::string& path)
{
    const json* cur = &root;
    std::stringstream ss(path);
    std::string key;
    while (std::getline(ss, key, '.')) {
        if (!cur->is_object()) return nullptr;
        auto it = cur->find(key);
        if (it == cur->end()) return nullptr;
        cur = &*it;
    }
    return cur;
}

const json& JsonReader::need(const json& root, const std::string& path) const
{
    const json* v = find(root, path);
    if (!v) fail(path, "is missing");
    return *v;
}

double JsonReader::number(const json& root, const std::string& path) const
{
    const json& v = need(root, path);
    if (!v.is_number()) fail(path, "must be a number, got " + describe_json(v));
    const double d = v.get<double>();
    if (!std::isfinite(d)) fail(path, "must be finite, got " + describe_json(v));
    return d;
}

double JsonReader::number_in(const json& root, const std::string& path, double lo, double hi, const std::string& unit) const
{
    const double d = number(root, path);
    if (d < lo || d > hi) {
        const std::string u = unit.empty() ? "" : " " + unit;
        fail(path, "= " + format_value(d) + u + " is outside [" + format_value(lo) + ", " + format_value(hi) + "]" + u);
    }
    return d;
}

double JsonReader::positive(const json& root, const std::string& path) const
{
    const double d = number(root, path);
    if (!(d > 0)) fail(path, "must be > 0, got " + describe_json(need(root, path)));
    return d;
}

std::optional<double> JsonReader::optional_number(const json& root, const std::string& path) const
{
    if (!find(root, path)) return std::nullopt;
    return number(root, path);
}

int JsonReader::integer(const json& root, const std::string& path, int min, int max) const
{
    const json& v = need(root, path);
    if (!v.is_number() || !std::isfinite(v.get<double>()) || std::floor(v.get<double>()) != v.get<double>())
        fail(path, "must be an integer, got " + describe_json(v));
    const double d = v.get<double>();
    if (d < min || d > max)
        fail(path, "must be an integer in [" + std::to_string(min) + ", " + std::to_string(max) + "], got " + describe_json(v));
    return static_cast<int>(d);
}

bool JsonReader::boolean(const json& root, const std::string& path) const
{
    const json& v = need(root, path);
    if (!v.is_boolean()) fail(path, "must be true or false, got " + describe_json(v));
    return v.get<bool>();
}

std::string JsonReader::string(const json& root, const std::string& path) const
{
    const json& v = need(root, path);
    if (!v.is_string()) fail(path, "must be a string, got " + describe_json(v));
    return v.get<std::string>();
}

std::vector<double> JsonReader::numbers(const json& root, const std::string& path, std::size_t n_expected) const
{
    const json& v = need(root, path);
    if (!v.is_array()) fail(path, "must be an array of numbers, got " + describe_json(v));
    if (n_expected && v.size() != n_expected)
        fail(path, "must have " + std::to_string(n_expected) + " entries, got " + std::to_string(v.size()));
    std::vector<double> out;
    for (std::size_t i = 0; i < v.size(); ++i) {
        if (!v[i].is_number() || !std::isfinite(v[i].get<double>()))
            fail(path + "[" + std::to_string(i) + "]", "must be a finite number, got " + describe_json(v[i]));
        out.push_back(v[i].get<double>());
    }
    return out;
}

} // namespace drape
