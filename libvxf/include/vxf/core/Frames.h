// vxf — frames of a shot: frame ranges as the command line gives them, and frame tokens in paths
// as Houdini ($F, $F4) and Blender (####) write them.
#pragma once

#include <string>
#include <vector>

namespace vxf {

/// The frames of @a spec, in the order given: `12` (one frame), `1-240` (inclusive), `1-240:2`
/// (every second frame from 1), and comma-separated lists of those (`1,5,10-20:5`), as Houdini's
/// and Blender's render commands take them. Frames are integers in [-999999, 9999999]; a frame
/// named twice is rendered once (where it first appears). Throws UsageError naming the part at
/// fault (`--frames: '240-1': the range runs backwards (240 > 1)`).
std::vector<int> parseFrameRange(const std::string& spec);

/// @a path with its frame tokens replaced by @a frame: `$F` (the frame as it is), `$F4` (zero-
/// padded to 4 digits; `$F2`..`$F9` alike; `${F}` and `${F4}` too) as Houdini writes them, and a
/// run of `#` (zero-padded to as many digits as there are `#`) as Blender writes them. Other
/// Houdini variables (`$FF`, `$FSTART`, `$HIP`) are refused by name: vxf cannot expand them.
std::string expandFrameTokens(const std::string& path, int frame);

/// Whether @a path holds a frame token. Never throws: a path without one (`$HOME/smoke.vdb`) is
/// a still path, taken as it is; expanding one that has both refuses the other variable.
bool hasFrameTokens(const std::string& path);

/// @a frame zero-padded to 4 digits as output names carry it (`NAME.0001.exr`; `-001` below zero).
std::string paddedFrame(int frame, int digits = 4);

} // namespace vxf
