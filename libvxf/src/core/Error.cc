#include <vxf/core/Error.h>

#include <fmt/format.h>

namespace vxf {

namespace {
std::string locate(const std::string& path, std::size_t line, std::size_t column)
{
    if (line == 0) return path;
    if (column == 0) return fmt::format("{}:{}", path, line);
    return fmt::format("{}:{}:{}", path, line, column);
}
} // namespace

InputError::InputError(const std::string& path, std::size_t line, std::size_t column, const std::string& what)
    : Error(locate(path, line, column) + ": " + what)
    , mPath(path)
    , mLine(line)
    , mColumn(column)
{
}

} // namespace vxf
