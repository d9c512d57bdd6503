// Text from users (engine/core/text.hpp): UTF-8 checks, NFC, fabric names and
// the message escaper, on arbitrary bytes. NFC is idempotent and keeps valid
// UTF-8; a normalised name normalises to itself; escaped text is printable.
#include "engine/core/error.hpp"
#include "engine/core/text.hpp"
#include "fuzz_common.hpp"

#include <cstdint>

using namespace drape;

DRAPE_FUZZ_TARGET(names)(const std::uint8_t* data, std::size_t size)
{
    const std::string s(reinterpret_cast<const char*>(data), size);
    const std::string p = printable(s, 1000);
    fuzz::require(is_valid_utf8(p), "escaped text is UTF-8");
    for (unsigned char c : p) fuzz::require(c >= 0x20 && c != 0x7f, "escaped text holds no control byte");
    if (!is_valid_utf8(s)) {
        fuzz::require(!try_normalize_name(s), "a name that is not UTF-8 is refused");
        return 0;
    }
    const std::string n = to_nfc(s);
    fuzz::require(is_valid_utf8(n), "NFC output is UTF-8");
    fuzz::require(to_nfc(n) == n, "NFC is idempotent");
    fuzz::require(utf8_length(n) <= 3 * utf8_length(s) + 3, "NFC growth is bounded");
    if (const auto name = try_normalize_name(s)) {
        fuzz::require(!name->empty() && utf8_length(*name) <= 200, "a name has 1..200 characters");
        fuzz::require(try_normalize_name(*name) == name, "a normalised name normalises to itself");
    }
    return 0;
}
