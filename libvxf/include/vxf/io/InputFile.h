// vxf — what every reader asks of a file before it opens it.
#pragma once

#include <cstdint>
#include <string>

namespace vxf {

/// vxf::InputError naming @a path unless it is a regular file (after symbolic links): "no such
/// file", "is a folder, not a file", "is not a regular file (a FIFO, device or socket)", "a loop
/// of symbolic links". A FIFO hung the readers (opened twice, never written) and /dev/zero
/// grew memory to the limit.
void requireRegularFile(const std::string& path);

/// The whole regular file at @a path, refused above @a maxBytes with an error stating the
/// bound (@a what: "a scene", "a pipeline graph").
std::string readBoundedFile(const std::string& path, std::uintmax_t maxBytes, const char* what);

} // namespace vxf
