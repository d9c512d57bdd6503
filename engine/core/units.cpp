#include "engine/core/units.hpp"

#include "engine/core/error.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace drape {

namespace {
std::string_view trim(std::string_view s)
{
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.front()))) s.remove_prefix(1);
    while (!s.empty() && std::isspace(static_cast<unsigned char>(s.back()))) s.remove_suffix(1);
    return s;
}
} // namespace

bool parse_number(std::string_view text, double& out)
{
    const std::string_view s = trim(text);
    if (s.empty()) return false;
    const char* first = s.data();
    if (*first == '+') ++first; // from_chars takes no leading '+'
    double v = 0;
    const auto [ptr, ec] = std::from_chars(first, s.data() + s.size(), v);
    if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v)) return false;
    out = v;
    return true;
}

double parse_length(const std::string& text, const std::string& what)
{
    const std::string_view s = trim(text);
    double value = 0.0;
    const char* first = s.data();
    const char* last = s.data() + s.size();
    auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr == first)
        throw ParameterError(what + ": '" + text + "' is not a length (expected e.g. 300mm, 30cm, 0.3m)");
    const std::string_view unit = trim(std::string_view(ptr, static_cast<std::size_t>(last - ptr)));
    double scale = 1.0;
    if (unit.empty() || unit == "m") scale = 1.0;
    else if (unit == "mm") scale = 1e-3;
    else if (unit == "cm") scale = 1e-2;
    else
        throw ParameterError(what + ": unknown length unit '" + std::string(unit) + "' in '" + text + "' (use mm, cm or m)");
    const double v = value * scale;
    if (!std::isfinite(v)) throw ParameterError(what + ": '" + text + "' is not finite");
    return v;
}

std::string format_double(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.17g", v);
    return buf;
}

std::string format_value(double v)
{
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.6g", v);
    return buf;
}

} // namespace drape
