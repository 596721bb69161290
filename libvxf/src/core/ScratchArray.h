// vxf — a fixed-size array whose elements start uninitialized (private to libvxf): scratch that
// a parallel loop writes whole before anything reads it. std::vector value-initializes, so one
// thread zeroes every page before the loop starts; here the loop's own first writes fault the
// pages in, on every thread (the bunny at dim 1024: 0.9 GB a per-voxel float array, and the
// light stage's setup had spent 10 s of one thread zeroing such arrays).
#pragma once

#include <cstddef>
#include <memory>
#include <type_traits>

namespace vxf::detail {

template <typename T>
class ScratchArray
{
    static_assert(std::is_trivially_default_constructible_v<T> && std::is_trivially_destructible_v<T>,
        "a scratch array's elements are left as allocated");

public:
    ScratchArray() = default;
    /// @a size elements, none of them written yet.
    explicit ScratchArray(std::size_t size)
        : mValues(size > 0 ? new T[size] : nullptr)
        , mSize(size)
    {
    }

    std::size_t size() const { return mSize; }
    bool empty() const { return mSize == 0; }
    T* data() { return mValues.get(); }
    const T* data() const { return mValues.get(); }
    T& operator[](std::size_t i) { return mValues[i]; }
    const T& operator[](std::size_t i) const { return mValues[i]; }

private:
    std::unique_ptr<T[]> mValues;
    std::size_t mSize = 0;
};

} // namespace vxf::detail
