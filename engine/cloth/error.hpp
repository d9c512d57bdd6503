#pragma once
// Error family thrown at API boundaries for bad input. Numerical outcomes are
// reported through status structs instead (see solver_status.hpp).
#include <stdexcept>
#include <string>

namespace drape {

/// Base of every error Drapekit throws for bad input. The message names what
/// was wrong and where (file, field, value).
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Bad file contents or a file that cannot be read.
class FileError : public Error {
public:
    using Error::Error;
};

/// A parameter or option out of its allowed range.
class ParameterError : public Error {
public:
    using Error::Error;
};

} // namespace drape
