// vxf — trilinear interpolation over the corners a predicate accepts (the rest left out).
#pragma once

#include <openvdb/Types.h> // openvdb::Vec3d, openvdb::Coord

#include <cmath>

namespace vxf {

/// The eight voxels around index point @a p and their trilinear weights.
struct TrilinearCell
{
    explicit TrilinearCell(const openvdb::Vec3d& p)
        : base(openvdb::Coord::floor(p))
    {
        const openvdb::Vec3d f = p - base.asVec3d();
        for (int corner = 0; corner < 8; ++corner) {
            weight[corner] = ((corner & 1) ? f[0] : 1.0 - f[0]) * ((corner & 2) ? f[1] : 1.0 - f[1]) * ((corner & 4) ? f[2] : 1.0 - f[2]);
        }
    }
    openvdb::Coord corner(int i) const { return base.offsetBy(i & 1, (i >> 1) & 1, (i >> 2) & 1); }

    openvdb::Coord base;
    double weight[8];
};

/// Trilinear interpolation of Vec3 @a values (anything with getValue(Coord)) at @a p over the
/// corners @a use accepts, the weights renormalised over them; with @a geometric, per channel
/// the weighted geometric mean where all its values used are positive (exact for a field
/// falling off exponentially), linear otherwise. Returns false, leaving @a out, when the
/// corners used carry less than @a minWeight of the weight.
template <typename Values, typename Use>
bool maskedTrilinear(
    const Values& values, const openvdb::Vec3d& p, const Use& use, openvdb::Vec3d& out, bool geometric = false, double minWeight = 0.5)
{
    const TrilinearCell cell(p);
    double total = 0.0;
    openvdb::Vec3d linear(0.0), logSum(0.0);
    bool positive[3] = {geometric, geometric, geometric};
    for (int i = 0; i < 8; ++i) {
        if (cell.weight[i] <= 0.0) continue;
        const openvdb::Coord c = cell.corner(i);
        if (!use(c)) continue;
        const openvdb::Vec3d v(values.getValue(c));
        total += cell.weight[i];
        linear += v * cell.weight[i];
        for (int ch = 0; ch < 3; ++ch) {
            if (!positive[ch]) continue;
            if (v[ch] > 0.0)
                logSum[ch] += cell.weight[i] * std::log(v[ch]);
            else
                positive[ch] = false;
        }
    }
    if (total < minWeight || total <= 0.0) return false;
    for (int ch = 0; ch < 3; ++ch) out[ch] = positive[ch] ? std::exp(logSum[ch] / total) : linear[ch] / total;
    return true;
}

} // namespace vxf
