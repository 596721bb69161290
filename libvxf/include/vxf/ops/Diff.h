// vxf — the thesis's difference export: where an edited grid differs from the original.
#pragma once

#include <vxf/core/Interrupter.h>

#include <openvdb/openvdb.h>

namespace vxf::ops {

/// D = B − A at the voxels where they differ by more than @a tolerance in any channel, or
/// where only one of them is active; inactive elsewhere (so D is as sparse as the edit).
/// Both float or both Vec3f, on one transform.
openvdb::GridBase::Ptr difference(const openvdb::GridBase& a, const openvdb::GridBase& b, double tolerance = 0.0);

/// A ← A + D on D's active voxels (which become active in A): A with the edit replayed.
void applyDifference(openvdb::GridBase& a, const openvdb::GridBase& d);

/// applyDifference, then blend the edit's edge: the voxels of A within @a radius voxels of
/// D's voxels (and not in D) are recomputed by blur_special from their neighbours, so the
/// edit fades into the rest ("difference + smooth" export). D's own voxels stay as set.
void applyDifferenceSmoothed(openvdb::GridBase& a, const openvdb::GridBase& d, int radius, Interrupter* interrupter = nullptr);

} // namespace vxf::ops
