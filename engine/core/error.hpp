#pragma once
// The error family thrown at API boundaries for bad input. Numerical outcomes
// (a solve that did not converge, a fit that hit its budget) are not errors:
// they come back in status structs (cloth::SolverStatus, estimate::FitResult).
#include <stdexcept>
#include <string>

namespace drape {

/// Base of every error Drapekit throws for bad input. The message names what
/// was wrong and where (file, field, value).
class Error : public std::runtime_error {
public:
    using std::runtime_error::runtime_error;
};

/// Bad file contents or a file that cannot be read or written.
class FileError : public Error {
public:
    using Error::Error;
};

/// A parameter or option out of its allowed range.
class ParameterError : public Error {
public:
    using Error::Error;
};

/// A name that is not in a collection (a fabric that is not in the library, a
/// built-in that does not exist). Callers that want "absent" as a normal answer
/// ask with find() instead of catching this.
class NotFoundError : public ParameterError {
public:
    using ParameterError::ParameterError;
};

} // namespace drape
