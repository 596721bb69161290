// vxf — all-or-nothing file output.
#pragma once

#include <functional>
#include <string>

namespace vxf {

/// Write @a path all or nothing: @a write is called with the path of a temporary file in
/// the same directory, which is renamed over @a path only when @a write returns. If it
/// throws, the temporary file is removed, @a path is left as it was and the exception
/// propagates — a failure never leaves a half-written output. The temporary is named
/// `.NAME.tmp-HOST-PID-N`; temporaries of @a path that a process of this host left when it was
/// killed (SIGKILL: no handler runs) are removed here, by the next write of the same path.
void writeAtomically(const std::string& path, const std::function<void(const std::string& tmpPath)>& write);

} // namespace vxf
