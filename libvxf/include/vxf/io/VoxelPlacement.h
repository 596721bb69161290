// vxf — where another tool's volume puts its voxels: centred on the grid's points (OpenVDB,
// Houdini) or over the cells after them (Blender, Cycles), read from what the file says of its writer.
#pragma once

#include <vxf/core/Scene.h>

#include <openvdb/Grid.h>

#include <string>

namespace vxf {

/// The placement a volume file asks for, and why (a phrase for a person).
struct PlacementChoice
{
    VoxelPlacement placement = VoxelPlacement::Centre; ///< Centre or Cell, never Auto
    std::string why;
};

/// Resolve @a requested for the file at @a path whose file-level metadata is @a fileMeta: an
/// explicit Centre or Cell stands; Auto is Cell for a file Blender wrote and Centre for every
/// other. Blender writes no writer metadata (checked: a geometry-nodes bake of bpy 4.5.15 and
/// Mantaflow's writer set only the grids' names, classes and transforms), so its files are
/// known by the names it gives them: Mantaflow's caches `fluid_data_NNNN.vdb` and
/// `fluid_noise_NNNN.vdb`, and a geometry-nodes bake's `blobs/NNNNN_NNNNN_file_N.vdb` beside its
/// `meta/` folder; a `creator` metadata naming Blender counts too. A file vxf or Houdini wrote
/// (their metadata: vxf's, `creator` "Houdini…") is Centre.
PlacementChoice resolvePlacement(VoxelPlacement requested, const std::string& path, const openvdb::MetaMap& fileMeta);

/// @a transform moved as @a placement says: for Cell, by half a voxel along each index axis
/// (applied before the grid's own map, so it follows a turned or stretched grid).
openvdb::math::Transform::Ptr placedTransform(const openvdb::math::Transform& transform, VoxelPlacement placement);

} // namespace vxf
