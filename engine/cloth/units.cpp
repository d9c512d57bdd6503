#include "units.hpp"

#include "error.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>

namespace drape {

double parse_length(const std::string& text, const std::string& what)
{
    std::size_t b = 0, e = text.size();
    while (b < e && std::isspace(static_cast<unsigned char>(text[b]))) ++b;
    while (e > b && std::isspace(static_cast<unsigned char>(text[e - 1]))) --e;
    const std::string s = text.substr(b, e - b);
    double value = 0.0;
    const char* first = s.data();
    const char* last = s.data() + s.size();
    auto [ptr, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || ptr == first)
        throw ParameterError(what + ": '" + text + "' is not a length (expected e.g. 300mm, 30cm, 0.3m)");
    std::string unit(ptr, last);
    while (!unit.empty() && std::isspace(static_cast<unsigned char>(unit.front()))) unit.erase(0, 1);
    double scale = 1.0;
    if (unit.empty() || unit == "m") scale = 1.0;
    else if (unit == "mm") scale = 1e-3;
    else if (unit == "cm") scale = 1e-2;
    else
        throw ParameterError(what + ": unknown length unit '" + unit + "' in '" + text + "' (use mm, cm or m)");
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

} // namespace drape
