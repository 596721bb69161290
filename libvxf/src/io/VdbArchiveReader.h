// vxf — reading a .vdb archive with every size the file declares checked before OpenVDB uses it.
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>
#include <functional>
#include <istream>
#include <string>
#include <vector>

namespace vxf::detail {

struct VdbArchive
{
    openvdb::GridPtrVec grids;
    openvdb::MetaMap metadata;
    /// Grids of types vxf does not read (point data, strings), skipped by their descriptor's end
    /// offset: "NAME (TYPE)".
    std::vector<std::string> skipped;
};

/// What openvdb::io::Stream reads (the header, the file's metadata, every grid), read by
/// OpenVDB's own functions in the same order, with a look-ahead before each that sizes memory
/// from the file: a string, a metadata value or a grid descriptor must fit in the bytes left
/// (@a fileBytes in all), and a fixed-size metadata value must declare its own size, so that
/// the look-ahead and OpenVDB read the same bytes. Grids of the voxel types (float, double,
/// int32, int64, bool, mask, Vec3 of float and double) are read; others (points, strings,
/// Vec3 of int) are skipped.
/// OpenVDB's delayed-load metadata (for reading a file piecewise, which vxf never does; its
/// reader sizes buffers from counts it does not check) is read as opaque bytes and dropped.
/// Files of format versions 222 (OpenVDB 1.0) to 224 (every later OpenVDB) are read.
/// With @a wanted, a voxel grid whose name it refuses is skipped by its descriptor's end offset
/// (read, then dropped, where the file gives none); a grid that is an instance of one skipped
/// throws (its tree is that grid's).
/// With @a headersOnly, each grid's metadata alone is read (no transform, no tree: the grids
/// are empty), the rest skipped by the descriptor's end offset (read whole where it gives none).
/// @a in must be seekable, with exceptions on (a read past the end throws). Throws
/// openvdb::IoError describing the first size that does not fit.
VdbArchive readVdbArchive(
    std::istream& in, std::uint64_t fileBytes, const std::function<bool(const std::string&)>& wanted = {}, bool headersOnly = false);

/// Once per process, before any .vdb is read: openvdb::initialize(), and the delayed-load
/// metadata type unregistered (above).
void initializeVdbReading();

} // namespace vxf::detail
