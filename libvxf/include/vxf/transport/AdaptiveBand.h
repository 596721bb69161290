// vxf — the adaptive narrow band: full resolution near the surface, the tree's tiles deeper.
#pragma once

#include <openvdb/openvdb.h>

namespace vxf {

struct AdaptiveBandReport
{
    openvdb::Index64 fineVoxels = 0; ///< active voxels left at full resolution
    std::size_t leafTiles = 0; ///< 8³ blocks made one value
    std::size_t internalTiles = 0; ///< 128³ blocks made one value
    openvdb::Index64 coarseVoxels = 0; ///< voxels those tiles cover
};

/// The mean of @a leaf's active values over all its 8³ voxels (inactive ones as 0): the value a
/// band's tile takes for it (coarsenBeyondBand, the light stage's band, a coarse cell's read).
openvdb::Vec3f leafMean(const openvdb::Vec3STree::LeafNodeType& leaf);

/// The deep interior beyond a band: the 8³ leaves whose voxels all lie at least max(band, 4
/// voxels) inside the medium (the active region of a density, eroded with the 26-neighbour (L∞)
/// stencil, so it never overstates the distance to the surface). coarsenBeyondBand makes them
/// tiles; the light stage with a band writes them so.
class BandInterior
{
public:
    /// @a band in world units; ≤ 0: no leaf is deep.
    BandInterior(const openvdb::FloatGrid& density, double band);
    /// Whether the leaf at @a origin lies wholly in the deep interior.
    bool holdsLeaf(const openvdb::Coord& origin) const;

private:
    openvdb::MaskTree mCore;
};

/// Coarsen the deep interior of @a grid (a quantity on the medium, e.g. a scattering source):
/// every 8³ leaf whose voxels all lie at least max(band, 4 voxels) inside the medium (the
/// active region of @a density) becomes one active tile holding the leaf's mean, and every
/// 128³ block at least max(band, 64 voxels) deep becomes one tile holding its mean — the
/// VDB tree's own levels, so each block's centre is never farther from its voxels than they
/// are from the band. Depth is measured by eroding the medium's topology with the 26-neighbour
/// (L∞) stencil, so it never overstates the distance to the surface. Means keep the grid's
/// sum (energy) unchanged. @a band is in world units; band ≤ 0 leaves @a grid untouched.
/// Passes over the tree evaluate tiles once (at their centre), so a pass costs the band's
/// voxels plus one per tile. Idempotent.
AdaptiveBandReport coarsenBeyondBand(openvdb::Vec3SGrid& grid, const openvdb::FloatGrid& density, double band);

/// A copy of @a grid coarsened as coarsenBeyondBand does it in place, the same values, made
/// without copying the leaves that become tiles: the scatter stage's own source, 12 bytes an
/// active voxel of the deep interior less than a copy coarsened afterwards. @a report as
/// coarsenBeyondBand's. Null where no block would become a tile (a source the light stage
/// wrote with the band already): @a grid itself is what a copy would be.
openvdb::Vec3SGrid::Ptr coarsenedBeyondBand(
    const openvdb::Vec3SGrid& grid, const openvdb::FloatGrid& density, double band, AdaptiveBandReport& report);

} // namespace vxf
