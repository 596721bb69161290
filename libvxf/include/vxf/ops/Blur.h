// vxf — blur a grid's active voxels.
#pragma once

#include <vxf/core/Interrupter.h>

#include <openvdb/openvdb.h>

namespace vxf::ops {

enum class BlurKind { Box, Distance };

struct BlurOptions
{
    BlurKind kind = BlurKind::Box; ///< box: mean over the (2r+1)³ neighbourhood; distance: Gaussian-weighted
    int radius = 1; ///< in voxels (≥ 1)
    int iterations = 1;
    const openvdb::FloatGrid* mask = nullptr; ///< blend blurred and original by this weight in [0,1] (null: everywhere)
};

/// Blur the active voxels of a float or Vec3f grid with OpenVDB's tools::Filter (separable
/// mean or Gaussian, per axis). Neighbours that are inactive contribute the background
/// value (as Houdini's VDB Smooth does), so values fade at the edge of the active region.
/// Topology unchanged: active tiles keep their value, inactive voxels stay inactive.
void blur(openvdb::GridBase& grid, const BlurOptions& options, Interrupter* interrupter = nullptr);

/// A float weight grid from a bool selection (1 where selected), for BlurOptions::mask.
openvdb::FloatGrid::Ptr weightsFromSelection(const openvdb::BoolGrid& selection);

} // namespace vxf::ops
