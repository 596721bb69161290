#include <vxf/scatter/SweepPass.h>

#include "PassSource.h"

#include <vxf/core/Hash.h>
#include <vxf/core/RandomRotation.h>
#include <vxf/core/SphericalFibonacci.h>

#include <openvdb/math/Mat3.h>

#include <algorithm>
#include <cmath>
#include <utility>

namespace vxf {

std::vector<openvdb::Vec3d> sweepDirections(int count, std::uint64_t seed)
{
    std::vector<openvdb::Vec3d> directions;
    if (count % 2 == 0) {
        for (const openvdb::Vec3d& d : sphericalFibonacci(count / 2)) {
            directions.push_back(d);
            directions.push_back(-d);
        }
    } else {
        directions = sphericalFibonacci(count);
    }
    // Isotropic second moments: ω ← M^{−1/2}ω, normalised, until M = (3/N) Σ ωωᵀ is I. (A
    // few iterations; the antipodal pairs keep Σ ω = 0.)
    for (int iteration = 0; iteration < 100 && directions.size() >= 3; ++iteration) {
        openvdb::Mat3d m = openvdb::Mat3d::zero();
        for (const openvdb::Vec3d& d : directions) m += openvdb::math::outerProduct(d, d);
        m *= 3.0 / double(directions.size());
        openvdb::Mat3d vectors;
        openvdb::Vec3d values;
        if (!openvdb::math::diagonalizeSymmetricMatrix(m, vectors, values)) break;
        double worst = 0.0;
        for (int a = 0; a < 3; ++a) worst = std::max(worst, std::abs(values[a] - 1.0));
        if (worst < 1e-12 || std::min({values[0], values[1], values[2]}) <= 1e-6) break;
        openvdb::Mat3d inverseRoot = openvdb::Mat3d::zero();
        for (int a = 0; a < 3; ++a) inverseRoot(a, a) = 1.0 / std::sqrt(values[a]);
        const openvdb::Mat3d transform = vectors * inverseRoot * vectors.transpose();
        for (openvdb::Vec3d& d : directions) d = (transform * d).unit();
    }
    if (seed == 0) return directions;
    const openvdb::Mat3d rotation = randomRotation(unitHash(seed, 0, 11), unitHash(seed, 1, 11), unitHash(seed, 2, 11));
    for (openvdb::Vec3d& d : directions) d = (rotation * d).unit();
    return directions;
}

openvdb::Vec3SGrid::Ptr sweepPass(
    const Medium& medium, const openvdb::Vec3SGrid& source, const ScatterPassOptions& options, Interrupter* interrupter)
{
    InterruptStep step(interrupter, "sweeping");
    const detail::SweepLattice lattice(medium, source);
    std::vector<openvdb::Vec3f> fluence(lattice.voxelCount(), openvdb::Vec3f(0.0f)), skin;
    if (options.directions >= 1) {
        const std::vector<openvdb::Vec3d> directions = sweepDirections(options.directions, options.rotationSeed);
        std::vector<openvdb::Vec3f> j = options.source == ScatterPassOptions::SourceRead::Continued
            ? detail::readPassSource(lattice, medium, source)
            : lattice.read(source);
        lattice.sweep(lattice.sweepSource(std::move(j)), directions, 4.0 * M_PI / double(directions.size()), fluence, &skin, interrupter);
    }
    lattice.putSkin(fluence, skin);
    auto grid = lattice.write(fluence, source);
    grid->setName("fluence");
    return grid;
}

} // namespace vxf
