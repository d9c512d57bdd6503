#pragma once
// Results the `drape` command prints are checked against their physical
// ranges first: a number that cannot be right is refused, not printed.
#include "engine/cloth/drape.hpp"

#include <string>

namespace drape::cli {

/// Empty when the drape's metrics lie in their physical ranges (finite; D in
/// [0, 100] %; node count in [0, 100]; hem between the floor and the
/// specimen's radius above the disc; radii within 1.5 specimen radii), else
/// one sentence naming the first value outside and its range.
std::string unphysical(const cloth::DrapeResult& r, const cloth::DrapeSetup& setup);

/// Throws drape::Error (exit 1) for a converged drape with unphysical metrics;
/// for a drape that did not reach rest, prints why on stderr and returns false
/// (the caller exits 4 without printing metrics). True when there is nothing to say.
bool check_drape_result(const cloth::DrapeResult& r, const cloth::DrapeSetup& setup);

} // namespace drape::cli
