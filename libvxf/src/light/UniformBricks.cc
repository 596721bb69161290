#include <vxf/light/UniformBricks.h>

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
    const float inside = float(-kDepth * dx), outside = float(kDepth * dx);

    mBricks.assign(std::size_t(mBrickDims[0]) * mBrickDims[1] * mBrickDims[2], kNotUniform);
    mUniformBricks = tbb::parallel_reduce(
        tbb::blocked_range<std::size_t>(0, mBricks.size()), std::size_t(0),
        [&](const tbb::blocked_range<std::size_t>& r, std::size_t found) {
            float values[kBrick + 2][kBrick + 2][kBrick + 2], distances[kBrick + 2][kBrick + 2][kBrick + 2];
            for (std::size_t n = r.begin(); n != r.end(); ++n) {
                const openvdb::Coord first = scaled(cellAt(n, mBrickOrigin, mBrickDims), kBrick) - openvdb::Coord(1);
                if (!density->getBlock(first, values)) continue; // reaches beyond the copy: read nowhere uniform
                // Wholly outside the surface: no step there has a part inside, whatever the density.
                if (hasSurface && surface->getBlock(first, distances) && all(distances, [&](float d) { return d >= outside; })) {
                    mBricks[n] = 0.0f;
                    ++found;
                    continue;
                }
                const float v = values[0][0][0];
                bool uniform = v >= 0.0f && std::isfinite(v) && all(values, [&](float x) { return x == v; });
                if (uniform && hasSurface) {
                    uniform = surface->getBlock(first, distances) && all(distances, [&](float d) { return d <= inside; });
                }
                if (!uniform) continue;
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
                const openvdb::Coord voxel = first.offsetBy(kBrick * (i / (perAxis * perAxis)), kBrick * ((i / perAxis) % perAxis), kBrick * (i % perAxis));
                const std::int64_t b = indexOf(voxel, kBrickShift, mBrickOrigin, mBrickDims);
                const float brick = b < 0 ? kNotUniform : mBricks[std::size_t(b)];
                uniform = brick == brick && (i == 0 || brick == v); // NaN: not uniform
                v = brick;
            }
            if (uniform) mBlocks[n] = v;
        }
    });
}

bool UniformBricks::find(const openvdb::Vec3d& p, openvdb::Vec3d& lo, openvdb::Vec3d& hi, float& value) const
{
    if (mBricks.empty()) return false;
    const openvdb::Coord voxel = openvdb::Coord::floor(p);
    const auto in = [&](const std::vector<float>& table, int shift, const openvdb::Coord& origin, const openvdb::Coord& dims) {
        const std::int64_t n = indexOf(voxel, shift, origin, dims);
        if (n < 0 || std::isnan(table[std::size_t(n)])) return false;
        value = table[std::size_t(n)];
        lo = scaled(shifted(voxel, shift), 1 << shift).asVec3d();
        hi = lo + openvdb::Vec3d(double(1 << shift));
        return true;
    };
    return in(mBlocks, kBlockShift, mBlockOrigin, mBlockDims) || in(mBricks, kBrickShift, mBrickOrigin, mBrickDims);
}

} // namespace vxf
