#include <vxf/io/GridChecksum.h>

#include <vxf/core/Hash.h>

#include <openvdb/openvdb.h>
#include <openvdb/math/Half.h>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstring>
#include <type_traits>
#include <vector>

namespace vxf {

namespace {

inline std::uint64_t combine(std::uint64_t h, std::uint64_t v) { return mixBits(h ^ mixBits(v)); }

template <typename T>
std::uint64_t bitsOf(const T& v, bool asHalf)
{
    if constexpr (std::is_same_v<T, float>) {
        if (asHalf) {
            const openvdb::math::half h(v);
            return std::uint64_t(h.bits());
        }
        std::uint32_t b = 0;
        std::memcpy(&b, &v, sizeof b);
        return b;
    } else if constexpr (std::is_same_v<T, bool>) {
        return v ? 1u : 0u;
    } else if constexpr (openvdb::VecTraits<T>::IsVec) {
        std::uint64_t h = 0;
        for (int i = 0; i < openvdb::VecTraits<T>::Size; ++i) h = combine(h, bitsOf(v[i], asHalf));
        return h;
    } else {
        static_assert(sizeof(T) <= 8, "a scalar of at most 8 bytes");
        std::uint64_t b = 0;
        std::memcpy(&b, &v, sizeof(T));
        return b;
    }
}

template <typename GridT>
std::uint64_t checksumOf(const GridT& grid, bool asHalf)
{
    using TreeT = typename GridT::TreeType;
    using LeafT = typename TreeT::LeafNodeType;
    const TreeT& tree = grid.tree();
    std::uint64_t h = combine(0x76786621u, bitsOf(tree.background(), asHalf));
    // Active tiles above the leaves, in the tree's order.
    typename TreeT::ValueOnCIter tile = tree.cbeginValueOn();
    tile.setMaxDepth(TreeT::ValueOnCIter::LEAF_DEPTH - 1);
    for (; tile; ++tile) {
        const openvdb::Coord c = tile.getCoord();
        h = combine(h, std::uint64_t(tile.getLevel()));
        h = combine(h, coordKey(c));
        h = combine(h, bitsOf(*tile, asHalf));
    }
    // Leaves: hashed in parallel, combined in order.
    std::vector<const LeafT*> leaves;
    leaves.reserve(tree.leafCount());
    tree.getNodes(leaves);
    std::vector<std::uint64_t> leafHash(leaves.size());
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves.size()), [&](const tbb::blocked_range<std::size_t>& r) {
        for (std::size_t n = r.begin(); n != r.end(); ++n) {
            const LeafT& leaf = *leaves[n];
            std::uint64_t lh = coordKey(leaf.origin());
            for (auto it = leaf.cbeginValueOn(); it; ++it) {
                lh = combine(lh, it.pos());
                lh = combine(lh, bitsOf(*it, asHalf));
            }
            leafHash[n] = lh;
        }
    });
    for (const std::uint64_t lh : leafHash) h = combine(h, lh);
    return h;
}

} // namespace

std::optional<std::uint64_t> gridChecksum(const openvdb::GridBase& grid, bool asHalf)
{
    if (const auto* g = dynamic_cast<const openvdb::FloatGrid*>(&grid)) return checksumOf(*g, asHalf);
    if (const auto* g = dynamic_cast<const openvdb::Vec3SGrid*>(&grid)) return checksumOf(*g, asHalf);
    if (const auto* g = dynamic_cast<const openvdb::DoubleGrid*>(&grid)) return checksumOf(*g, false);
    if (const auto* g = dynamic_cast<const openvdb::Vec3DGrid*>(&grid)) return checksumOf(*g, false);
    if (const auto* g = dynamic_cast<const openvdb::Int32Grid*>(&grid)) return checksumOf(*g, false);
    if (const auto* g = dynamic_cast<const openvdb::Int64Grid*>(&grid)) return checksumOf(*g, false);
    if (const auto* g = dynamic_cast<const openvdb::Vec3IGrid*>(&grid)) return checksumOf(*g, false);
    if (const auto* g = dynamic_cast<const openvdb::BoolGrid*>(&grid)) return checksumOf(*g, false);
    return std::nullopt;
}

std::string checksumText(std::uint64_t checksum) { return fmt::format("{:016x}", checksum); }

} // namespace vxf
