// vxf — a scatter pass's source as the sweeps read it (private to libvxf's scatter module).
#pragma once

#include "transport/lattice/SweepLattice.h"

#include <vxf/scatter/SourceField.h>

#include <tbb/enumerable_thread_specific.h>

#include <vector>

namespace vxf::detail {

/// A pass's source (σs·φ/4π of a fluence whose skin voxels hold the light on the surface, as
/// SweepLattice::putSkin and the gathers give it) as a sweep steps it, from centre to centre:
/// read on @a lattice, its skin voxels' values at their centres (SweepLattice::skinAtCentres,
/// from SourceField's lattice read). Read as it is, the thick bunny's second order came out 7%
/// below the gather's (the first 1.7%).
inline std::vector<openvdb::Vec3f> readPassSource(const SweepLattice& lattice, const Medium& medium, const openvdb::Vec3SGrid& source)
{
    std::vector<openvdb::Vec3f> j = lattice.read(source);
    if (!medium.surface()) return j;
    const SourceField field(medium, source, SourceField::Near::Lattice);
    tbb::enumerable_thread_specific<SourceField::Sampler> samplers([&field] { return SourceField::Sampler(field); });
    lattice.skinAtCentres(j, [&](const openvdb::Coord& c) { return openvdb::Vec3f(samplers.local().sample(c.asVec3d())); });
    return j;
}

} // namespace vxf::detail
