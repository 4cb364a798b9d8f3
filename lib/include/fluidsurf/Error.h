// Error.h - the exceptions fluidsurf throws. The library never calls exit(); the CLI turns an
// exception into one line on stderr and a non-zero exit code.
#pragma once

#include <stdexcept>
#include <string>

namespace fluidsurf {

/// Base of every fluidsurf exception.
class Error : public std::runtime_error
{
public:
    explicit Error(const std::string& msg) : std::runtime_error(msg) {}
};

/// A file (or in-memory buffer) that cannot be read: truncated, corrupt, wrong format.
/// The message names the source and, where known, the byte offset of the problem.
class InputError : public Error
{
public:
    explicit InputError(const std::string& msg) : Error(msg) {}
};

/// A file that cannot be written (permissions, disk full, unsupported output format).
class OutputError : public Error
{
public:
    explicit OutputError(const std::string& msg) : Error(msg) {}
};

/// A parameter outside its valid range.
class ValueError : public Error
{
public:
    explicit ValueError(const std::string& msg) : Error(msg) {}
};

} // namespace fluidsurf
