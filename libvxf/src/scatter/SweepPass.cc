#include <vxf/scatter/SweepPass.h>

#include "SweepLattice.h"

#include <vxf/core/Hash.h>
#include <vxf/core/RandomRotation.h>
#include <vxf/core/SphericalFibonacci.h>

#include <cmath>

namespace vxf {

std::vector<openvdb::Vec3d> sweepDirections(int count, std::uint64_t seed)
{
    std::vector<openvdb::Vec3d> directions = sphericalFibonacci(count);
    if (seed == 0) return directions;
    const openvdb::Mat3d rotation = randomRotation(unitHash(seed, 0, 11), unitHash(seed, 1, 11), unitHash(seed, 2, 11));
    for (openvdb::Vec3d& d : directions) d = (rotation * d).unit();
    return directions;
}

openvdb::Vec3SGrid::Ptr sweepPass(const Medium& medium, const openvdb::Vec3SGrid& source, const ScatterPassOptions& options,
    Interrupter* interrupter)
{
    InterruptStep step(interrupter, "sweeping");
    const detail::SweepLattice lattice(medium, source);
    std::vector<openvdb::Vec3f> fluence(lattice.voxelCount(), openvdb::Vec3f(0.0f));
    if (options.directions >= 1) {
        const std::vector<openvdb::Vec3d> directions = sweepDirections(options.directions, options.rotationSeed);
        lattice.sweep(lattice.sweepSource(lattice.read(source)), directions, 4.0 * M_PI / double(directions.size()), fluence, interrupter);
    }
    auto grid = lattice.write(fluence, source);
    grid->setName("fluence");
    return grid;
}

} // namespace vxf
