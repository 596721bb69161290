// vxf — values per lattice voxel held a leaf's block at a time (private to light/), so that each
// block can be freed once it has been read: the light stage's swept sums give their memory back
// leaf by leaf as the output grids' leaves are made from them.
#pragma once

#include "../transport/SweepLattice.h"

#include <cstddef>
#include <memory>
#include <vector>

namespace vxf::detail {

template <typename T>
class LeafBlocks
{
public:
    static constexpr std::size_t kBlock = SweepLattice::kLeafVoxels;

    bool empty() const { return mBlocks.empty(); }
    /// @a leaves blocks of kBlock values, each @a value.
    void assign(std::size_t leaves, const T& value)
    {
        mBlocks.clear();
        mBlocks.resize(leaves);
        for (auto& block : mBlocks) {
            block.reset(new T[kBlock]);
            std::fill(block.get(), block.get() + kBlock, value);
        }
    }
    /// Lattice voxel @a i (leaf i / kBlock); its block must not have been released.
    T& operator[](std::size_t i) { return mBlocks[i / kBlock][i % kBlock]; }
    const T& operator[](std::size_t i) const { return mBlocks[i / kBlock][i % kBlock]; }
    /// Frees leaf @a leaf's block (distinct leaves may be released from distinct threads).
    void release(std::size_t leaf) { mBlocks[leaf].reset(); }

private:
    std::vector<std::unique_ptr<T[]>> mBlocks;
};

} // namespace vxf::detail
