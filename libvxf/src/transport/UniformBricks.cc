#include <vxf/transport/UniformBricks.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vxf {

namespace {

constexpr int kBrickShift = 2, kBlockShift = 4; // 4 = 1 << 2, 16 = 1 << 4
constexpr float kNotUniform = std::numeric_limits<float>::quiet_NaN();

openvdb::Coord shifted(const openvdb::Coord& c, int shift) { return openvdb::Coord(c[0] >> shift, c[1] >> shift, c[2] >> shift); }

/// (Right shifts of negative coordinates round down, as floor division does; scaling back multiplies,
/// since left shifts of negative numbers are undefined.)
openvdb::Coord scaled(const openvdb::Coord& c, int size) { return openvdb::Coord(c[0] * size, c[1] * size, c[2] * size); }

openvdb::Coord cellAt(std::size_t n, const openvdb::Coord& origin, const openvdb::Coord& dims)
{
    const std::size_t nz = std::size_t(dims[2]), ny = std::size_t(dims[1]);
    return origin.offsetBy(int(n / (ny * nz)), int((n / nz) % ny), int(n % nz));
}

/// Whether @a test holds for every value of @a block.
template <typename Block, typename Test>
bool all(const Block& block, const Test& test)
{
    const float* first = &block[0][0][0];
    return std::all_of(first, first + sizeof(Block) / sizeof(float), test);
}

} // namespace

std::int64_t UniformBricks::indexOf(const openvdb::Coord& ijk, int shift, const openvdb::Coord& origin, const openvdb::Coord& dims)
{
    const openvdb::Coord c = shifted(ijk, shift) - origin;
    if (c[0] < 0 || c[1] < 0 || c[2] < 0 || c[0] >= dims[0] || c[1] >= dims[1] || c[2] >= dims[2]) return -1;
    return (std::int64_t(c[0]) * dims[1] + c[1]) * dims[2] + c[2];
}

UniformBricks::UniformBricks(const DenseCopy<openvdb::FloatGrid>* density, const openvdb::CoordBBox& bounds,
    const DenseCopy<openvdb::FloatGrid>* surface, double dx, bool hasSurface)
{
    static_assert(kBrick == 1 << kBrickShift && kBlock == 1 << kBlockShift);
    if (!density || bounds.empty() || (hasSurface && !surface)) return;
    // Trilinear reads reach a voxel beyond the medium (marchBounds).
    const openvdb::Coord lo = bounds.min().offsetBy(-1), hi = bounds.max().offsetBy(1);
    mBrickOrigin = shifted(lo, kBrickShift);
    mBrickDims = shifted(hi, kBrickShift) - mBrickOrigin + openvdb::Coord(1);
    mBlockOrigin = shifted(lo, kBlockShift);
    mBlockDims = shifted(hi, kBlockShift) - mBlockOrigin + openvdb::Coord(1);
    const float inside = float(-kInside * dx), outside = float(kOutside * dx);

    // Per brick: a density ≥ 0 (inside), −(least distance to the surface, voxels) (outside), NaN.
    mBricks.assign(std::size_t(mBrickDims[0]) * mBrickDims[1] * mBrickDims[2], kNotUniform);
    mUniformBricks = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, mBricks.size()), std::size_t(0),
        [&](const tbb::blocked_range<std::size_t>& r, std::size_t found) {
            float values[kBrick + 2][kBrick + 2][kBrick + 2], distances[kBrick + 2][kBrick + 2][kBrick + 2];
            for (std::size_t n = r.begin(); n != r.end(); ++n) {
                const openvdb::Coord first = scaled(cellAt(n, mBrickOrigin, mBrickDims), kBrick) - openvdb::Coord(1);
                if (hasSurface) {
                    if (!surface->getBlock(first, distances)) continue; // reaches beyond the copy: not uniform
                    const float least = *std::min_element(&distances[0][0][0], &distances[0][0][0] + sizeof(distances) / sizeof(float));
                    // Wholly outside the surface: no step there has a part inside, whatever the density.
                    if (least >= outside) {
                        mBricks[n] = -float(least / dx);
                        ++found;
                        continue;
                    }
                    if (!all(distances, [&](float d) { return d <= inside; })) continue;
                }
                if (!density->getBlock(first, values)) continue;
                const float v = values[0][0][0];
                if (!(v >= 0.0f && std::isfinite(v) && all(values, [&](float x) { return x == v; }))) continue;
                mBricks[n] = v;
                ++found;
            }
            return found;
        },
        [](std::size_t a, std::size_t b) { return a + b; });

    constexpr int perAxis = kBlock / kBrick;
    mBlocks.assign(std::size_t(mBlockDims[0]) * mBlockDims[1] * mBlockDims[2], kNotUniform);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, mBlocks.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            const openvdb::Coord first = scaled(cellAt(n, mBlockOrigin, mBlockDims), kBlock);
            float v = kNotUniform;
            bool uniform = true;
            for (int i = 0; uniform && i < perAxis * perAxis * perAxis; ++i) {
                const openvdb::Coord voxel =
                    first.offsetBy(kBrick * (i / (perAxis * perAxis)), kBrick * ((i / perAxis) % perAxis), kBrick * (i % perAxis));
                const std::int64_t b = indexOf(voxel, kBrickShift, mBrickOrigin, mBrickDims);
                const float brick = b < 0 ? kNotUniform : mBricks[std::size_t(b)];
                if (std::isnan(brick)) {
                    uniform = false;
                } else if (i == 0) {
                    v = brick;
                } else if (v < 0.0f && brick < 0.0f) {
                    v = std::max(v, brick); // outside: the least distance of all
                } else {
                    uniform = brick == v; // inside: one density
                }
            }
            if (uniform) mBlocks[n] = v;
        }
    });
}

UniformBricks::UniformBricks(openvdb::FloatGrid::ConstPtr density)
    : mTree(std::move(density))
{
}

bool UniformBricks::findInTree(const openvdb::Vec3d& p, openvdb::Vec3d& lo, openvdb::Vec3d& hi, float& density) const
{
    using Tree = openvdb::FloatTree;
    using Upper = Tree::RootNodeType::ChildNodeType;
    using Lower = Upper::ChildNodeType;
    const openvdb::Coord voxel = openvdb::Coord::floor(p);
    const Tree& tree = mTree->tree();
    // The depth of the node holding voxel's value: −1 the background beyond the root's nodes, 0 a
    // root tile, 1 and 2 the internal nodes' tiles, 3 a leaf's voxel (not a region).
    const int depth = tree.getValueDepth(voxel);
    const int size = depth <= 0 ? int(Upper::DIM) : depth == 1 ? int(Lower::DIM) : depth == 2 ? int(Lower::ChildNodeType::DIM) : 0;
    if (size == 0) return false;
    const float value = tree.getValue(voxel);
    if (!(value >= 0.0f && std::isfinite(value))) return false;
    const openvdb::Coord first(voxel[0] & ~(size - 1), voxel[1] & ~(size - 1), voxel[2] & ~(size - 1));
    // Points whose reads (their floor voxel and the next) stay inside, a voxel from either face.
    lo = first.asVec3d() + openvdb::Vec3d(1.0);
    hi = first.asVec3d() + openvdb::Vec3d(double(size - 1));
    for (int a = 0; a < 3; ++a) {
        if (p[a] < lo[a] || p[a] >= hi[a]) return false;
    }
    density = value;
    return true;
}

bool UniformBricks::find(const openvdb::Vec3d& p, double step, openvdb::Vec3d& lo, openvdb::Vec3d& hi, float& density) const
{
    if (mTree) return findInTree(p, lo, hi, density);
    if (mBricks.empty()) return false;
    const openvdb::Coord voxel = openvdb::Coord::floor(p);
    const auto in = [&](const std::vector<float>& table, int shift, const openvdb::Coord& origin, const openvdb::Coord& dims) {
        const std::int64_t n = indexOf(voxel, shift, origin, dims);
        if (n < 0) return false;
        const float value = table[std::size_t(n)];
        if (std::isnan(value)) return false;
        // Outside, a step's two ends lie at least 2·least from the surface together: no dip inside
        // for a step up to that long (InsideSteps), with a margin for rounding.
        if (value < 0.0f && !(-2.0 * value >= 1.001 * step)) return false;
        density = std::max(value, 0.0f);
        lo = scaled(shifted(voxel, shift), 1 << shift).asVec3d();
        hi = lo + openvdb::Vec3d(double(1 << shift));
        return true;
    };
    return in(mBlocks, kBlockShift, mBlockOrigin, mBlockDims) || in(mBricks, kBrickShift, mBrickOrigin, mBrickDims);
}

int UniformBricks::stepsWithin(const openvdb::Vec3d& p, const openvdb::Vec3d& direction, double step, int most, float& density) const
{
    openvdb::Vec3d lo, hi;
    if (most < 2 || !find(p, step, lo, hi, density)) return 0;
    double leave = std::numeric_limits<double>::max();
    for (int a = 0; a < 3; ++a) {
        if (direction[a] > 0.0) leave = std::min(leave, (hi[a] - p[a]) / direction[a]);
        if (direction[a] < 0.0) leave = std::min(leave, (lo[a] - p[a]) / direction[a]);
    }
    const int count = std::min(most, int(std::ceil(leave / step)) - 1);
    return count < 2 ? 0 : count;
}

} // namespace vxf
