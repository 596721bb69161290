// vxf — errors thrown by libvxf.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>

namespace vxf {

/// Base of every exception libvxf throws. The message is complete and meant for a person:
/// it names the file, line, column or parameter at fault. Front ends print it as
/// `vxf: <command>: <message>` and exit with status 1.
class Error : public std::runtime_error
{
public:
    explicit Error(const std::string& message)
        : std::runtime_error(message)
    {
    }
};

/// A bad parameter value or combination (front ends exit with status 2).
class UsageError : public Error
{
public:
    explicit UsageError(const std::string& message)
        : Error(message)
    {
    }
};

/// Malformed input file content. The message starts with `file:line:column: `
/// (line and column are 1-based; 0 means "the whole file" / "the whole line").
class InputError : public Error
{
public:
    InputError(const std::string& path, std::size_t line, std::size_t column, const std::string& what);
    const std::string& path() const { return mPath; }
    std::size_t line() const { return mLine; }
    std::size_t column() const { return mColumn; }

private:
    std::string mPath;
    std::size_t mLine, mColumn;
};

/// The operation was cancelled through its interrupter; no output was written.
class Interrupted : public Error
{
public:
    Interrupted()
        : Error("interrupted")
    {
    }
};

} // namespace vxf
