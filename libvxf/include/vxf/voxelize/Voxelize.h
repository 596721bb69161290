// vxf — mesh → voxel set (`surface` level set and `density` fog volume).
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/StageDefaults.h>
#include <vxf/core/TriangleMesh.h>
#include <vxf/core/VoxelSet.h>

namespace vxf {

struct VoxelizeOptions
{
    double voxelSize = 0.0; ///< world units per voxel; 0: derive from @c dim
    int dim = 0; ///< voxels along the longest side of the mesh bounds (if voxelSize is 0)
    float bandWidth = float(defaults::kBand); ///< narrow band half width in voxels, each side of the surface (≥ 1)
    /// Voxelize on this lattice (a linear transform, e.g. voxelLattice() of several meshes'
    /// bounds) instead of one derived from the mesh; voxelSize and dim are then ignored.
    openvdb::math::Transform::ConstPtr lattice;
};

/// meshToVolume's peak per narrow-band voxel (822 MB for the bunny's 14.9M at dim 1024,
/// issue 59), what voxelize checks against the memory budget before it allocates.
inline constexpr double kVoxelizeBytesPerBandVoxel = 56.0;
/// The smallest voxel size (world units): OpenVDB's transforms refuse a scale whose cube is
/// below 3e-15.
inline constexpr double kMinVoxelSize = 1.5e-5;

/// The index space vxf voxelizes @a bounds into: voxel centres on voxelSize·ℤ³, the index
/// origin shifted by whole voxels to the bounds' centre when they lie over 2^16 voxels from
/// the world origin (so float index coordinates keep sub-voxel precision).
openvdb::math::Transform::Ptr voxelLattice(const openvdb::BBoxd& bounds, double voxelSize);

/// The voxel size @a options ask for on meshes spanning @a bounds (validates them; throws
/// vxf::UsageError, or vxf::Error for empty bounds).
double resolveVoxelSize(const openvdb::BBoxd& bounds, const VoxelizeOptions& options);

/// Voxelize a closed triangle mesh with OpenVDB's mesh-to-volume.
///
/// Produces `surface`, a narrow-band level set (active voxels within bandWidth voxels of the
/// surface on each side, inactive tiles of ±background elsewhere) and `density`, a fog
/// volume: 1 inside (deep interior kept as active tiles, never voxelized), in the band each
/// voxel's volume fraction clamp(½ − φ/dx, 0, 1) (so the medium ends at the mesh surface:
/// trilinear lookups cross ½ there), inactive 0 outside. The index space is voxelLattice() of the
/// mesh's bounds, or options.lattice.
/// Before allocating, the band's voxels are estimated as the surface's area in voxels times the
/// band's full width (2·bandWidth; the interior is tiles): a peak (kVoxelizeBytesPerBandVoxel
/// each) above the memory budget (core/MemoryBudget.h) is a vxf::Error naming the numbers, a
/// voxel size below kMinVoxelSize a vxf::UsageError, not an allocation that fails.
/// Results do not depend on the number of threads. Throws vxf::UsageError for bad options,
/// vxf::Error for an empty mesh, vxf::Interrupted when cancelled.
VoxelSet voxelize(const TriangleMesh& mesh, const VoxelizeOptions& options, Interrupter* interrupter = nullptr);

} // namespace vxf
