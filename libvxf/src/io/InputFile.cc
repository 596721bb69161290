#include <vxf/io/InputFile.h>

#include <vxf/core/Error.h>
#include <vxf/io/ContentHash.h>

#include <fmt/format.h>

#include <filesystem>

namespace vxf {

void requireRegularFile(const std::string& path)
{
    namespace fs = std::filesystem;
    std::error_code error;
    const fs::file_status status = fs::status(path, error);
    if (error && error == std::errc::too_many_symbolic_link_levels) {
        throw InputError(path, 0, 0, "a loop of symbolic links, not a file");
    }
    if (!fs::exists(status)) throw InputError(path, 0, 0, "no such file");
    if (fs::is_directory(status)) throw InputError(path, 0, 0, "is a folder, not a file");
    if (!fs::is_regular_file(status)) {
        throw InputError(path, 0, 0, "is not a regular file (a FIFO, device or socket); vxf reads files");
    }
}

std::string readBoundedFile(const std::string& path, std::uintmax_t maxBytes, const char* what)
{
    std::error_code error; // (not a regular file: no size here, and readFileBytes names why)
    const std::uintmax_t size = std::filesystem::file_size(path, error);
    if (!error && size > maxBytes) {
        throw InputError(path, 0, 0, fmt::format("{} bytes; {} may have at most {} MiB", size, what, maxBytes >> 20));
    }
    return readFileBytes(path);
}

} // namespace vxf
