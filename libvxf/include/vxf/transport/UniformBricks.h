// vxf — where every march step is alike (uniform inside the surface, or wholly outside it), to cross in one go.
#pragma once

#include <vxf/core/GridLookup.h>

#include <openvdb/openvdb.h>

#include <cstdint>
#include <vector>

namespace vxf {

/// The bricks of 4³ voxels (and the blocks of 16³) over which a march's steps are all alike,
/// so that a march crosses them in one go instead of a step at a time: the same sum to
/// rounding, a fraction of the lookups. Two kinds:
/// - inside: every voxel a step's lookups can read holds the same density and lies half a voxel
///   or more inside the surface, so that InsideSteps takes each step whole, finds no crossing to
///   snap, and Medium::Sampler::interiorScale is 1 (all eight voxels whole). A voxelized mesh's
///   interior is this (density 1, in tiles); without a surface, any run of equal density.
/// - outside: every voxel lies outside the surface by kOutside or more, so no step (up to twice
///   that long) there has a part inside (InsideSteps counts nothing, whatever the density
///   holds): density 0 for the march. The empty space light from outside crosses to the medium.
/// An edited or simulated density is uniform almost nowhere and costs nothing but the table.
///
/// A brick's voxels and the one-voxel shell around them (6³: all that trilinear and
/// interiorScale reads at points whose floor lies in the brick touch) are tested: one density
/// ≥ 0 and, with a surface, signed distances ≤ −kInside voxels; or signed distances ≥ kOutside.
/// A block is uniform when its 64 bricks are, inside with one density or all outside. The
/// tables are dense over the medium's bounds, one float per brick and one per block (NaN: not
/// uniform), and are built only from dense copies (GridLookup's, themselves bounded by
/// kDenseCopyBytes): a table is at most a 64th of one.
class UniformBricks
{
public:
    static constexpr int kBrick = 4, kBlock = 16;
    /// Voxels: how far inside the surface every voxel of an inside brick lies. From −½ a voxel
    /// is whole (interiorScale's fractions are 1) and a step's ends lie beyond
    /// Medium::kSnapWindow, where InsideSteps looks for no crossing; a hundredth more for rounding.
    static constexpr double kInside = 0.51;
    /// Voxels: how far outside the surface every voxel of an outside brick lies at least: beyond
    /// Medium::kQuadraticBand (signedDistance reads them trilinearly, never below the least
    /// voxel). A step whose ends lie sa + sb ≥ its length outside cannot dip inside, so a brick
    /// whose voxels lie d or more outside serves steps up to 2d (find).
    static constexpr double kOutside = 0.26;

    /// The table of a medium's @a density (its dense copy) over its active @a bounds, with
    /// @a surface the march surface's dense copy (world distances, voxel size @a dx) when
    /// @a hasSurface. Empty (find always false) without a density copy, or without a surface
    /// copy where there is a surface.
    UniformBricks(const DenseCopy<openvdb::FloatGrid>* density, const openvdb::CoordBBox& bounds,
        const DenseCopy<openvdb::FloatGrid>* surface, double dx, bool hasSurface);

    /// Without a dense copy (a grid too large for one, e.g. a simulation's puffs far apart) and
    /// without a surface: the regions are the density tree's own tiles and the background
    /// between its nodes (Tree::getValueDepth), 8³ to 4096³ voxels of one value, less a voxel
    /// at their faces (trilinear reads reach the next voxel), so that a march crosses the empty
    /// space between a sparse grid's parts in one go rather than a step at a time.
    explicit UniformBricks(openvdb::FloatGrid::ConstPtr density);

    /// The uniform region holding index-space point @a p for march steps of @a step voxels (a
    /// block where there is one, else a brick) as its closed-open box [lo, hi) of points whose
    /// floor lies in it, and its @a density (0 outside the surface); false where @a p lies in no
    /// such region.
    bool find(const openvdb::Vec3d& p, double step, openvdb::Vec3d& lo, openvdb::Vec3d& hi, float& density) const;

    /// The whole steps of @a step voxels from @a p along unit @a direction that lie in the
    /// region holding @a p (at most @a most; 0 for fewer than two, or no region), every step's
    /// end strictly before the region's far face (a point on it reads beyond), with the
    /// region's @a density.
    int stepsWithin(const openvdb::Vec3d& p, const openvdb::Vec3d& direction, double step, int most, float& density) const;

    /// Bricks found uniform (for reports and tests).
    std::size_t uniformBrickCount() const { return mUniformBricks; }

private:
    /// The index in a table of cells of 2^@a shift voxels (first cell @a origin, @a dims cells
    /// per axis) of the cell holding voxel @a ijk, or −1 outside it.
    static std::int64_t indexOf(const openvdb::Coord& ijk, int shift, const openvdb::Coord& origin, const openvdb::Coord& dims);

    openvdb::Coord mBrickOrigin, mBrickDims, mBlockOrigin, mBlockDims; ///< in bricks, in blocks
    std::vector<float> mBricks, mBlocks;
    openvdb::FloatGrid::ConstPtr mTree; ///< the tree's regions instead of the tables'
    /// The tree's region holding index point @a p (find's), if any.
    bool findInTree(const openvdb::Vec3d& p, openvdb::Vec3d& lo, openvdb::Vec3d& hi, float& density) const;
    std::size_t mUniformBricks = 0;
};

} // namespace vxf
