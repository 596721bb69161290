// vxf — the text VXF format's columns and lattice, shared by its reader (VxfTextRead.cc) and
// writer (VxfTextWrite.cc); private to io/.
#pragma once

#include <openvdb/openvdb.h>

#include <cmath>
#include <string>

namespace vxf::detail {

enum class ColumnType { Bool, Float, Vec3 };

inline int columnWidth(ColumnType type) { return type == ColumnType::Vec3 ? 3 : 1; }

inline const char* columnTypeName(ColumnType type)
{
    switch (type) {
    case ColumnType::Bool: return "bool";
    case ColumnType::Float: return "float";
    case ColumnType::Vec3: return "vec3";
    }
    return "?";
}

/// One grid stored as one (bool, float) or three (vec3) columns of each voxel line.
struct GridColumn
{
    std::string name;
    ColumnType type = ColumnType::Vec3;
    openvdb::GridClass gridClass = openvdb::GRID_UNKNOWN;
    openvdb::Vec3f background{0.0f};
};

/// Whether the corner @a minCorner of text voxel (0, 0, 0) lies on the voxel corners of a
/// transform that only scales by @a voxelSize (min/voxelsize + ½ integral to within 1e-6 on
/// every axis, as vdb2vxf writes it for such grids, which vxf's own are, and within 2¹⁶ voxels
/// of the origin); then that voxel's
/// index under it in @a origin. Text voxel (i, j, k) is then VDB voxel origin + (i, j, k), so
/// that a round trip keeps every voxel's index coordinates (and leaves, tiles, and the
/// alignment with the sibling grids of the .vdb it came from).
inline bool originOnLattice(const openvdb::Vec3d& minCorner, double voxelSize, openvdb::Coord& origin)
{
    for (int a = 0; a < 3; ++a) {
        const double index = minCorner[a] / voxelSize + 0.5, nearest = std::round(index);
        // (Far from the origin vxf's lattices are translated instead: see voxelLattice.)
        if (!(std::abs(index - nearest) <= 1e-6) || std::abs(nearest) > double(1 << 16)) return false;
        origin[a] = openvdb::Int32(nearest);
    }
    return true;
}

/// The transform of a text header's voxels (see originOnLattice): a uniform scale by
/// @a voxelSize, translated so that voxel (0, 0, 0)'s centre is min + voxelsize/2 unless min
/// lies on the scale's own lattice (@a origin then holds that voxel's index, else 0).
inline openvdb::math::Transform::Ptr textTransform(const openvdb::Vec3d& minCorner, double voxelSize, openvdb::Coord& origin)
{
    auto xform = openvdb::math::Transform::createLinearTransform(voxelSize);
    if (!originOnLattice(minCorner, voxelSize, origin)) {
        origin = openvdb::Coord(0);
        xform->postTranslate(minCorner + openvdb::Vec3d(0.5 * voxelSize));
    }
    return xform;
}

} // namespace vxf::detail
