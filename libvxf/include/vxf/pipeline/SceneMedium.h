// vxf — a scene's participating medium as one voxel set: its media objects voxelized together.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/VoxelSet.h>
#include <vxf/core/Scene.h>
#include <vxf/voxelize/Voxelize.h>

#include <string>

namespace vxf {

/// The scene's media on one voxel lattice, ready for the light stage.
/// - One medium object: voxelize() of its (world-space) mesh; a volume object's grid as
///   `density` on its own voxels (moved by its transform), no `surface`; when @a options give a
///   voxel size or dim, those voxels coarsened by halvings to the nearest power of two
///   (OpenVDB's MultiResGrid, full-weighting restriction: the medium's mass kept), never refined,
///   and @a note (when given) says what was chosen. A volume object must be the only medium.
/// - Several: each is voxelized on the lattice of their joint bounds (dim counts voxels along
///   the longest side of all of them); `surface` is their CSG union, `density` the per-voxel
///   maximum, and `sigma_a` / `sigma_s` (Vec3f) hold Σ_i density_i·σ_i, so each object keeps its
///   own material and superposed media add where they overlap (Medium then reads the grids).
/// Then the material's own per-voxel coefficient grids, if it names any (attachMaterialGrids).
/// Sparse throughout: interior tiles stay tiles. Throws vxf::UsageError when the scene has no
/// medium, or per-voxel grids are given with several media.
VoxelSet voxelizeMedia(const Scene& scene, const VoxelizeOptions& options, Interrupter* interrupter = nullptr, std::string* note = nullptr);

/// The voxelize options @a settings ask for (voxel_size over dim, the band); a volume object's
/// are 0 unless its scene gives them (its own voxels).
VoxelizeOptions sceneVoxelizeOptions(const SceneSettings& settings);

/// The world bounds of volume object @a object's active voxels, placed and moved as
/// voxelizeMedia places them (its grid read in full; throws as voxelizeMedia does).
openvdb::BBoxd volumeBounds(const SceneObject& object);

/// Put @a material's per-voxel coefficient grids (Material::gridsFile, sigmaAGrid, sigmaSGrid)
/// into @a set as `sigma_a` / `sigma_s`, resampled trilinearly onto the set's transform when
/// theirs differs. No-op when the material names no file. Throws vxf::InputError naming the
/// file and grid when a grid is missing or not Vec3f.
void attachMaterialGrids(VoxelSet& set, const Material& material);

/// The material the stages record and plan with: the one medium's; with several media the
/// per-channel maximum of their coefficients (the voxel set's sigma grids carry each object's
/// own). Throws vxf::UsageError naming the scene when it has no medium.
Material sceneMaterial(const Scene& scene);

/// How many of the scene's objects are media.
int mediaCount(const Scene& scene);

} // namespace vxf
