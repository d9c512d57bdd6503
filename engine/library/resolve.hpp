#pragma once
// Where a fabric comes from when a person names it: a preset file, a built-in,
// a fabric of their library, or one of the starter fabrics; and the user's
// library itself, created with the starter fabrics on first use.
#include "engine/fabric/preset.hpp"
#include "engine/library/fabric_library.hpp"

#include <optional>
#include <string>

namespace drape::library {

/// The fabric `name` names in `lib`: the one stored under that name, else,
/// for a starter fabric's short or full name ("silk"), the one stored under
/// the starter's full name ("Silk (class preset)"); nullopt when neither is
/// stored. The one name lookup in a library: resolve_fabric (simulate,
/// predict, garment, the widget, ...) and `drape library show|export` use it.
std::optional<FabricRecord> find_fabric(const FabricLibrary& lib, const std::string& name);

/// What `drape library show|export NAME` shows: find_fabric's record, else a
/// starter fabric `lib` does not hold (removed, or another library) as an
/// unstored record (id 0, revision 0, no dates), which is what resolve_fabric
/// would drape. NotFoundError naming the library and the name otherwise.
FabricRecord library_fabric(const FabricLibrary& lib, const std::string& name);

/// The fabric `name` names, tried in this order: an existing preset file; a
/// built-in ("seed-table1"); a fabric of the library at `library_path` (the
/// default library when empty, fabric_library.hpp) by find_fabric; a starter
/// fabric by short name (silk, cotton, wool, denim) or full name. Throws
/// FileError for a file that is not a valid preset, NotFoundError saying what
/// was tried otherwise.
fabric::FabricPreset resolve_fabric(const std::string& name, const std::string& library_path = {});

/// Opens the library at `path` (the default library when empty). The default
/// library is created on first use, holding the starter fabrics, even for a
/// read-only command: a brand-new user's `drape library list` shows fabrics.
/// A library named explicitly is never created by a read-only open.
FabricLibrary open_library(const std::string& path, FabricLibrary::Mode mode);

/// Adds the starter fabrics that are not in `lib` yet (by name); returns how many were added.
int add_starter_fabrics(FabricLibrary& lib);

} // namespace drape::library
