// vxf — one scattering pass by discrete-ordinates sweeps over the tree.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/transport/Medium.h>
#include <vxf/scatter/ScatterPass.h>

#include <cstdint>
#include <vector>

namespace vxf {

/// The sweep kernel: φ(x) = Σ_i (4π/N) ψ(x, ω_i), where for each of the N spherical Fibonacci
/// directions (turned as a whole by options.rotationSeed) the radiance ψ solves
/// ω·∇ψ = −σt ψ + J with no light entering from outside the medium's leaves. Each direction is
/// one upwind sweep over the leaves of the medium and of @a source (tiles voxelized): leaves in
/// wavefronts along the direction's octant (those of one wavefront in parallel), voxels inside
/// a leaf in upwind order, each voxel from the four voxels upwind of it — short
/// characteristics: the ray from its centre back to the previous layer of centres across the
/// direction's dominant axis, ψ, J and σt there interpolated bilinearly (weights in [0, 1]: ψ
/// stays positive and bounded), the medium only over the step's part inside the surface (see
/// SweepLattice), the source function J/σt linear in optical depth along it, integrated exactly
/// (finite for σt from 0 to ∞, J/σt where a step is optically thick). O(1) per voxel and
/// direction: a few reads and one exp per channel (one for grey media), no march. Voxels of the leaves that hold no medium
/// (σt = 0) carry light across as it is; light leaving the leaves is gone (light crossing
/// a gap wider than a leaf between two parts of a concave medium is lost).
///
/// Ray effects: a volume source is spread over the medium, so the discrete directions show
/// little; what they leave, options.rotationSeed moves (scatter() turns each pass's set).
/// Numerical diffusion: the bilinear upwind read spreads a beam sideways by about a voxel per
/// voxel travelled obliquely; the fluence, an angular integral, feels it near sharp edges.
/// Output: a Vec3f grid named "fluence" on @a source's topology (an active tile holds the mean
/// of its voxels), its skin voxels (centre within half a voxel of the surface) holding the
/// fluence on the surface, as the gather's do. Results do not depend on the thread count (each voxel is computed by one
/// thread from values final before its wavefront; directions add in a fixed order: octant by
/// octant, in the order given within one).
/// Cost: (voxels of the touched leaves) × directions, the directions of an octant taking a leaf
/// in turn while it is in cache (about 18-20 ns per voxel and direction on 2 cores); memory: the
/// source and fluence, and of each leaf only its three downwind faces per direction in flight.
openvdb::Vec3SGrid::Ptr sweepPass(
    const Medium& medium, const openvdb::Vec3SGrid& source, const ScatterPassOptions& options = {}, Interrupter* interrupter = nullptr);

/// The sweep kernel's directions: for an even @a count, sphericalFibonacci(count/2) and their
/// opposites (Σ ω = 0, and each direction's reverse is swept too), made isotropic in their
/// second moments (Σ ωωᵀ = N/3·I: the diffusion coefficient the sweeps' multiple scattering
/// carries is the same along every axis; spherical Fibonacci's 16 points alone were 5.6% low
/// along one axis and 3.8% high along another, and light that crossed many mean free paths
/// came out several percent off), turned by the random rotation seeded by @a seed (identity for 0).
std::vector<openvdb::Vec3d> sweepDirections(int count, std::uint64_t seed);

} // namespace vxf
