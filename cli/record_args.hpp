#pragma once
// The RECORD_DIR arguments of the commands that take several records (fit,
// compare): one record given twice would count twice.
#include <string>
#include <vector>

namespace drape::cli {

/// Throws UsageError (exit 2) naming both spellings and the folder when two of
/// `dirs` are the same record folder: the same path spelled another way
/// ("rec", "rec/", "./rec", "../here/rec", an absolute path) or reached through
/// a symbolic link. Folders that do not exist are compared by their spelling
/// made absolute and normal (their own error comes later, from the reader).
void reject_duplicate_records(const std::vector<std::string>& dirs);

} // namespace drape::cli
