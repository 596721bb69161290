#include <vxf/core/Scene.h>

namespace vxf {

openvdb::Vec3d Material::albedo() const
{
    const openvdb::Vec3d t = sigmaT();
    openvdb::Vec3d a(0.0);
    for (int c = 0; c < 3; ++c) a[c] = t[c] > 0.0 ? sigmaS[c] / t[c] : 0.0;
    return a;
}

} // namespace vxf
