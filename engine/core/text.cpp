#include "engine/core/text.hpp"

#include "engine/core/error.hpp"
#include "engine/core/unicode_nfc_data.hpp"

#include <algorithm>
#include <cstdio>
#include <vector>

namespace drape {

namespace {

constexpr char32_t kInvalid = 0xFFFFFFFF;

/// Decodes one code point at s[i] and advances i; kInvalid (advancing one
/// byte) on a malformed sequence.
char32_t decode(std::string_view s, std::size_t& i)
{
    const auto b = [&](std::size_t k) { return static_cast<unsigned char>(s[k]); };
    const unsigned c0 = b(i);
    if (c0 < 0x80) {
        ++i;
        return c0;
    }
    int n = 0;
    char32_t cp = 0, min = 0;
    if (c0 >= 0xC2 && c0 <= 0xDF) n = 1, cp = c0 & 0x1F, min = 0x80;
    else if (c0 >= 0xE0 && c0 <= 0xEF) n = 2, cp = c0 & 0x0F, min = 0x800;
    else if (c0 >= 0xF0 && c0 <= 0xF4) n = 3, cp = c0 & 0x07, min = 0x10000;
    else {
        ++i;
        return kInvalid;
    }
    if (s.size() - i <= static_cast<std::size_t>(n)) {
        ++i;
        return kInvalid;
    }
    for (int k = 1; k <= n; ++k) {
        const unsigned c = b(i + static_cast<std::size_t>(k));
        if ((c & 0xC0) != 0x80) {
            ++i;
            return kInvalid;
        }
        cp = (cp << 6) | (c & 0x3F);
    }
    if (cp < min || cp > 0x10FFFF || (cp >= 0xD800 && cp <= 0xDFFF)) {
        ++i;
        return kInvalid;
    }
    i += static_cast<std::size_t>(n) + 1;
    return cp;
}

void encode(char32_t cp, std::string& out)
{
    if (cp < 0x80) {
        out += static_cast<char>(cp);
    } else if (cp < 0x800) {
        out += static_cast<char>(0xC0 | (cp >> 6));
        out += static_cast<char>(0x80 | (cp & 0x3F));
    } else if (cp < 0x10000) {
        out += static_cast<char>(0xE0 | (cp >> 12));
        out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (cp & 0x3F));
    } else {
        out += static_cast<char>(0xF0 | (cp >> 18));
        out += static_cast<char>(0x80 | ((cp >> 12) & 0x3F));
        out += static_cast<char>(0x80 | ((cp >> 6) & 0x3F));
        out += static_cast<char>(0x80 | (cp & 0x3F));
    }
}

std::vector<char32_t> code_points(std::string_view s)
{
    std::vector<char32_t> out;
    out.reserve(s.size());
    for (std::size_t i = 0; i < s.size();) {
        const char32_t cp = decode(s, i);
        if (cp == kInvalid) throw ParameterError("text '" + printable(s) + "' is not valid UTF-8");
        out.push_back(cp);
    }
    return out;
}

// ---- NFC (Unicode Standard Annex #15) -----------------------------------------

constexpr char32_t kSBase = 0xAC00, kLBase = 0x1100, kVBase = 0x1161, kTBase = 0x11A7;
constexpr char32_t kLCount = 19, kVCount = 21, kTCount = 28, kNCount = kVCount * kTCount, kSCount = kLCount * kNCount;

int combining_class(char32_t cp)
{
    using unicode::kCombining;
    const auto* end = kCombining + unicode::kCombiningCount;
    const auto* it = std::upper_bound(kCombining, end, cp, [](char32_t c, const unicode::CombiningRange& r) { return c < r.first; });
    if (it == kCombining) return 0;
    --it;
    return cp <= it->last ? it->klass : 0;
}

void decompose(char32_t cp, std::vector<char32_t>& out)
{
    if (cp >= kSBase && cp < kSBase + kSCount) {
        const char32_t s = cp - kSBase;
        out.push_back(kLBase + s / kNCount);
        out.push_back(kVBase + (s % kNCount) / kTCount);
        if (s % kTCount != 0) out.push_back(kTBase + s % kTCount);
        return;
    }
    using unicode::kDecompositions;
    const auto* end = kDecompositions + unicode::kDecompositionCount;
    const auto* it = std::lower_bound(kDecompositions, end, cp, [](const unicode::Decomposition& d, char32_t c) { return d.cp < c; });
    if (it != end && it->cp == cp) {
        for (int k = 0; k < it->length; ++k) out.push_back(unicode::kDecompositionPool[it->offset + k]);
        return;
    }
    out.push_back(cp);
}

char32_t compose(char32_t a, char32_t b)
{
    if (a >= kLBase && a < kLBase + kLCount && b >= kVBase && b < kVBase + kVCount)
        return kSBase + ((a - kLBase) * kVCount + (b - kVBase)) * kTCount;
    if (a >= kSBase && a < kSBase + kSCount && (a - kSBase) % kTCount == 0 && b > kTBase && b < kTBase + kTCount)
        return a + (b - kTBase);
    using unicode::kCompositions;
    const auto* end = kCompositions + unicode::kCompositionCount;
    const auto* it = std::lower_bound(kCompositions, end, std::pair{a, b}, [](const unicode::Composition& c, std::pair<char32_t, char32_t> k) {
        return c.first < k.first || (c.first == k.first && c.second < k.second);
    });
    if (it != end && it->first == a && it->second == b) return it->composite;
    return 0;
}

std::vector<char32_t> nfc(const std::vector<char32_t>& in)
{
    std::vector<char32_t> d;
    d.reserve(in.size() + 4);
    for (char32_t cp : in) decompose(cp, d);
    // Canonical ordering: a stable sort of every run of non-starters by class.
    for (std::size_t i = 0; i < d.size();) {
        if (combining_class(d[i]) == 0) {
            ++i;
            continue;
        }
        std::size_t j = i;
        while (j < d.size() && combining_class(d[j]) != 0) ++j;
        std::stable_sort(d.begin() + static_cast<std::ptrdiff_t>(i), d.begin() + static_cast<std::ptrdiff_t>(j),
                         [](char32_t a, char32_t b) { return combining_class(a) < combining_class(b); });
        i = j;
    }
    // Canonical composition: each character joins the last starter unless a
    // character in between blocks it (class 0, or a class >= its own).
    constexpr std::size_t kNone = static_cast<std::size_t>(-1);
    std::vector<char32_t> out;
    out.reserve(d.size());
    std::size_t starter = kNone; // index in `out` of the last starter
    int last_class = 0;          // class of the last character appended
    for (char32_t c : d) {
        const int cc = combining_class(c);
        if (starter != kNone && (last_class < cc || last_class == 0)) {
            // last_class == 0: the last character appended is the starter itself.
            if (const char32_t comp = compose(out[starter], c)) {
                out[starter] = comp;
                continue;
            }
        }
        if (cc == 0) starter = out.size();
        last_class = cc;
        out.push_back(c);
    }
    return out;
}

bool is_space(char32_t c)
{
    return (c >= 0x09 && c <= 0x0D) || c == 0x20 || c == 0x85 || c == 0xA0 || c == 0x1680 || (c >= 0x2000 && c <= 0x200B) ||
           c == 0x2028 || c == 0x2029 || c == 0x202F || c == 0x205F || c == 0x3000 || c == 0xFEFF;
}

/// Characters no name may hold: C0 and C1 controls, DEL, line and paragraph
/// separators, bidirectional embeddings, overrides and isolates (they make a
/// name display as another).
const char* forbidden(char32_t c)
{
    if (c < 0x20 || (c >= 0x7F && c <= 0x9F)) return "a control character";
    if (c == 0x2028 || c == 0x2029) return "a line or paragraph separator";
    if ((c >= 0x202A && c <= 0x202E) || (c >= 0x2066 && c <= 0x2069) || c == 0x200E || c == 0x200F || c == 0x061C)
        return "a bidirectional control character";
    return nullptr;
}

std::string hex(char32_t c)
{
    char buf[16];
    std::snprintf(buf, sizeof buf, "U+%04X", static_cast<unsigned>(c));
    return buf;
}

} // namespace

std::size_t first_invalid_utf8(std::string_view s)
{
    for (std::size_t i = 0; i < s.size();) {
        const std::size_t at = i;
        if (decode(s, i) == kInvalid) return at;
    }
    return std::string_view::npos;
}

bool is_valid_utf8(std::string_view s) { return first_invalid_utf8(s) == std::string_view::npos; }

std::size_t utf8_length(std::string_view s)
{
    std::size_t n = 0;
    for (std::size_t i = 0; i < s.size(); ++n) decode(s, i);
    return n;
}

std::string to_nfc(std::string_view s)
{
    std::string out;
    for (char32_t cp : nfc(code_points(s))) encode(cp, out);
    return out;
}

const char* unicode_version() { return unicode::kUnicodeVersion; }

namespace {
/// The normalised name, or the reason it has none.
std::string normalize_or_reason(std::string_view name, std::size_t max_chars, bool& ok)
{
    ok = false;
    if (!is_valid_utf8(name)) return "is not valid UTF-8 text";
    std::vector<char32_t> cps = nfc(code_points(name));
    std::size_t a = 0, b = cps.size();
    while (a < b && is_space(cps[a])) ++a;
    while (b > a && is_space(cps[b - 1])) --b;
    if (a == b) return "is empty (or only white space)";
    if (b - a > max_chars)
        return "is " + std::to_string(b - a) + " characters long, more than " + std::to_string(max_chars);
    for (std::size_t i = a; i < b; ++i)
        if (const char* why = forbidden(cps[i])) return std::string("contains ") + why + " (" + hex(cps[i]) + ")";
    std::string out;
    for (std::size_t i = a; i < b; ++i) encode(cps[i], out);
    ok = true;
    return out;
}
} // namespace

std::string normalize_name(std::string_view name, const std::string& what, std::size_t max_chars)
{
    bool ok = false;
    std::string r = normalize_or_reason(name, max_chars, ok);
    if (!ok) throw ParameterError(what + " '" + printable(name, 40) + "' " + r);
    return r;
}

std::optional<std::string> try_normalize_name(std::string_view name, std::size_t max_chars)
{
    bool ok = false;
    std::string r = normalize_or_reason(name, max_chars, ok);
    if (!ok) return std::nullopt;
    return r;
}

std::string ascii_lower(std::string_view s)
{
    std::string out(s);
    for (char& c : out)
        if (c >= 'A' && c <= 'Z') c = static_cast<char>(c - 'A' + 'a');
    return out;
}

std::string trim_blanks(std::string_view s)
{
    const auto b = s.find_first_not_of(" \t");
    if (b == std::string_view::npos) return {};
    return std::string(s.substr(b, s.find_last_not_of(" \t") - b + 1));
}

std::string printable(std::string_view s, std::size_t max_chars)
{
    std::string out;
    std::size_t chars = 0;
    for (std::size_t i = 0; i < s.size();) {
        if (chars == max_chars) {
            out += "...";
            break;
        }
        const std::size_t start = i;
        const char32_t cp = decode(s, i);
        char buf[8];
        if (cp == kInvalid) {
            std::snprintf(buf, sizeof buf, "\\x%02X", static_cast<unsigned char>(s[start]));
            out += buf;
        } else if (cp == '\n') {
            out += "\\n";
        } else if (cp == '\t') {
            out += "\\t";
        } else if (cp < 0x20 || (cp >= 0x7F && cp <= 0x9F)) {
            std::snprintf(buf, sizeof buf, "\\x%02X", static_cast<unsigned>(cp));
            out += buf;
        } else {
            out.append(s.substr(start, i - start));
        }
        ++chars;
    }
    return out;
}

} // namespace drape
