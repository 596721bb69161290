// vxf — values per lattice voxel held a leaf's block at a time (private to light/), so that each
// block can be freed once it has been read: the light stage's swept sums give their memory back
// leaf by leaf as the output grids' leaves are made from them.
#pragma once

#include "transport/lattice/SweepLattice.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
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
    /// @a leaves blocks of kBlock values, each @a value (made on every thread: the bunny at dim
    /// 1024 holds 2.6 GB of them, 5 s of one thread's page faults).
    void assign(std::size_t leaves, const T& value)
    {
        mBlocks.clear();
        mBlocks.resize(leaves);
        tbb::parallel_for(tbb::blocked_range<std::size_t>(0, leaves), [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t n = r.begin(); n != r.end(); ++n) {
                mBlocks[n].reset(new T[kBlock]);
                std::fill(mBlocks[n].get(), mBlocks[n].get() + kBlock, value);
            }
        });
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
