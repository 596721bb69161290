// vxf — the light stage for a scene: its material, lights and occluders on a voxel set.
#pragma once

#include <vxf/light/DirectLight.h>
#include <vxf/core/Scene.h>

namespace vxf {

/// Light @a set with @a scene: attach the material's coefficient grids (if it names any),
/// check that several media come with per-voxel sigma grids (voxelizeMedia), build the
/// occluders' Embree scene, run computeDirectLight and record the material in the set's
/// metadata (so scatter and render read it from the file). @a options.occluders is set here;
/// with @a options.similarity the medium lit is the similarity relation's (Medium::isotropic()).
/// Throws vxf::UsageError naming the scene for a multi-media scene on a single-medium set.
/// The light stage's options from a scene's settings: the march step (scatter.step), the band
/// (scatter.band: the deep leaves written as tiles, which the scatter's band takes them as), and
/// the similarity relation's medium unless the scatter the settings ask for carries a phase's
/// first moment (carriesFirstMoment).
DirectLightOptions lightOptionsFrom(const SceneSettings& settings);

DirectLightReport lightScene(VoxelSet& set, const Scene& scene, DirectLightOptions options = {}, Interrupter* interrupter = nullptr);

} // namespace vxf
