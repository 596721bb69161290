// vxf — split a Vec3f grid into float channels and merge them back (Houdini's Cd.x/y/z).
#pragma once

#include <openvdb/openvdb.h>

#include <array>
#include <string>

namespace vxf::ops {

/// Three float grids NAME.x, NAME.y, NAME.z (Houdini's naming) with @a grid's topology
/// (tiles stay tiles), transform and metadata; the background splits likewise.
std::array<openvdb::FloatGrid::Ptr, 3> splitChannels(const openvdb::Vec3SGrid& grid);

/// A Vec3f grid named @a name from three float grids on one transform: active where any is
/// active; a channel inactive there contributes its grid's background value.
openvdb::Vec3SGrid::Ptr mergeChannels(
    const openvdb::FloatGrid& x, const openvdb::FloatGrid& y, const openvdb::FloatGrid& z, const std::string& name);

} // namespace vxf::ops
