// bench/voxelize: the baseline — a bare OpenVDB meshToLevelSet call, nothing else vxf does.
// Usage: bare_mesh_to_level_set MESH OUT.vdb DIM [BAND]
// Reads the mesh with the same CGAL reader as vxf (no repair), picks the voxel size as vxf
// does for --dim (longest side / DIM), converts with tools::meshToLevelSet, writes the level
// set with Blosc, and prints one JSON line: seconds per step and active voxels.
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>

#include <openvdb/io/File.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

int main(int argc, char** argv)
{
    if (argc < 4) {
        std::fprintf(stderr, "usage: %s MESH OUT.vdb DIM [BAND]\n", argv[0]);
        return 2;
    }
    using Clock = std::chrono::steady_clock;
    const auto seconds = [](Clock::time_point a, Clock::time_point b) { return std::chrono::duration<double>(b - a).count(); };
    openvdb::initialize();
    const int dim = std::atoi(argv[3]);
    const float band = argc > 4 ? float(std::atof(argv[4])) : 3.0f;

    const auto t0 = Clock::now();
    std::vector<CGAL::Epick::Point_3> cgalPoints;
    std::vector<std::vector<std::size_t>> polygons;
    if (!CGAL::IO::read_polygon_soup(argv[1], cgalPoints, polygons)) {
        std::fprintf(stderr, "cannot read %s\n", argv[1]);
        return 1;
    }
    std::vector<openvdb::Vec3s> points;
    openvdb::BBoxd bounds;
    for (const auto& p : cgalPoints) {
        points.emplace_back(float(p.x()), float(p.y()), float(p.z()));
        bounds.expand(openvdb::Vec3d(p.x(), p.y(), p.z()));
    }
    std::vector<openvdb::Vec3I> triangles;
    for (const auto& f : polygons) {
        for (std::size_t i = 1; i + 1 < f.size(); ++i) triangles.emplace_back(f[0], f[i], f[i + 1]);
    }
    const auto t1 = Clock::now();
    const double voxelSize = bounds.extents()[bounds.maxExtent()] / double(dim);
    auto xform = openvdb::math::Transform::createLinearTransform(voxelSize);
    auto grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, points, triangles, band);
    grid->setName("surface");
    const auto t2 = Clock::now();
    openvdb::io::File file(argv[2]);
    file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
    file.write({grid});
    file.close();
    const auto t3 = Clock::now();
    std::printf("{\"read\": %.4f, \"mesh_to_level_set\": %.4f, \"write\": %.4f, \"total\": %.4f, "
                "\"voxel_size\": %.9g, \"active_voxels\": %llu}\n",
        seconds(t0, t1), seconds(t1, t2), seconds(t2, t3), seconds(t0, t3), voxelSize,
        static_cast<unsigned long long>(grid->activeVoxelCount()));
    return 0;
}
