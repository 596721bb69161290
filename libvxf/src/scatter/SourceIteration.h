// vxf — plain source iteration, one scattering order per pass (private to scatter/): the passes
// of scatter() when the sum is not solved whole (passes kept, continued or coarse, or no
// acceleration), with the series' tail and the coarse lattice's return to the fine one.
#pragma once

#include <vxf/scatter/Scatter.h>

#include <algorithm>
#include <string>

namespace vxf::detail {

inline double maxChannel(const openvdb::Vec3d& v) { return std::max({v[0], v[1], v[2]}); }

inline openvdb::Vec3SGrid::Ptr named(openvdb::Vec3SGrid::Ptr grid, const std::string& name)
{
    grid->setName(name);
    return grid;
}

/// The passes from source @a j (pass @a k next; @a sum holds the passes before it, summed in
/// place) as @a options says, reported in @a report: SourceIteration in SourceIteration.cc.
void iterateSources(VoxelSet& set, const Medium& medium, const ScatterOptions& options, ScatterReport& report, Interrupter* interrupter,
    openvdb::Vec3SGrid::Ptr sum, openvdb::Vec3SGrid::Ptr j, int k);

} // namespace vxf::detail
