// Voxelizes a built-in sphere, writes it, reads it back and lights it with one point light,
// through the umbrella header alone: what a program linking vxf::vxf can do.
#include <vxf/vxf.h>

#include <cstdio>

int main(int argc, char** argv)
{
    if (argc != 2) {
        std::fprintf(stderr, "usage: consumer OUT.vdb\n");
        return 2;
    }
    try {
        vxf::VoxelizeOptions options;
        options.dim = 24;
        vxf::writeVoxelSet(argv[1], vxf::voxelize(vxf::makeSphere(openvdb::Vec3d(0.0), 1.0), options));
        vxf::VoxelSet set = vxf::readVoxelSet(argv[1]);
        vxf::Material material;
        material.sigmaS = openvdb::Vec3d(4.0);
        const vxf::Medium medium(set, material);
        vxf::Light light;
        light.type = vxf::Light::Type::Point;
        light.position = openvdb::Vec3d(0.0, -3.0, 2.0);
        light.intensity = 10.0;
        vxf::computeDirectLight(set, medium, {light});
        std::printf("lit %llu voxels of %s\n", static_cast<unsigned long long>(set.find("direct")->activeVoxelCount()), argv[1]);
        return 0;
    } catch (const vxf::Error& e) {
        std::fprintf(stderr, "consumer: %s\n", e.what());
        return 1;
    }
}
