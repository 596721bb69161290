// vxf — a coarser copy of a voxel lattice for the smooth, high scattering orders.
#pragma once

#include <vxf/core/VoxelSet.h>
#include <vxf/transport/Medium.h>

#include <openvdb/openvdb.h>

#include <memory>

namespace vxf {

/// The transform of a lattice @a factor times coarser than @a fine whose voxel i covers the
/// fine voxels factor·i … factor·i + factor − 1 on each axis (its centre is their centre).
openvdb::math::Transform::Ptr coarseTransform(const openvdb::math::Transform& fine, int factor);

/// The mean of @a fine over each coarse voxel's block of factor³ fine voxels (inactive
/// fine voxels count as zero, so a half-covered coarse voxel holds half the density), on
/// @a coarse (from coarseTransform with the same factor). Active tiles contribute by volume.
/// Active where any fine value of the block is. Exact in total: Σ coarse·factor³ = Σ fine.
openvdb::FloatGrid::Ptr blockAverage(const openvdb::FloatGrid& fine, int factor, const openvdb::math::Transform::Ptr& coarse);
openvdb::Vec3SGrid::Ptr blockAverage(const openvdb::Vec3SGrid& fine, int factor, const openvdb::math::Transform::Ptr& coarse);

/// Trilinear interpolation of @a coarse at the centres of @a fine's active voxels (active
/// tiles: at their centre): a grid with @a fine's topology, transform and name.
openvdb::Vec3SGrid::Ptr prolong(const openvdb::Vec3SGrid& coarse, const openvdb::Vec3SGrid& fine);

/// A medium @a factor times coarser than @a medium: block averages of its density and,
/// when present, of its `sigma_a` / `sigma_s` grids, with the same material. The coarse
/// voxel set lives as long as the returned object.
struct CoarseMedium
{
    openvdb::math::Transform::Ptr transform; ///< coarseTransform(medium.transform(), factor)
    VoxelSet set;
    std::unique_ptr<Medium> medium;
};
CoarseMedium coarsenMedium(const Medium& medium, int factor);

} // namespace vxf
