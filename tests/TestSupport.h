// Helpers shared by the tests: temporary folders, running the real binaries, materials and
// constant fluence grids, exact grid comparison.
#pragma once

#include <vxf/core/VoxelSet.h>
#include <vxf/pipeline/SceneFile.h>

#include <nlohmann/json.hpp>
#include <openvdb/openvdb.h>

#include <filesystem>
#include <string>

namespace vxf::test {

/// A fresh empty folder under the system temp dir, removed on destruction.
class TempDir
{
public:
    TempDir();
    ~TempDir();
    std::string path(const std::string& name) const { return (mPath / name).string(); }
    const std::filesystem::path& root() const { return mPath; }

private:
    std::filesystem::path mPath;
};

/// Result of running a command line through the shell.
struct RunResult
{
    int status = -1;
    std::string out, err;
};

/// Run @a commandLine (a shell command) and capture its exit status, stdout and stderr.
RunResult run(const std::string& commandLine);

/// Path of a built binary (vxf, vxf2vdb, vdb2vxf, bench/...).
std::string binary(const std::string& name);

/// Path of a file in the source tree.
std::string source(const std::string& relative);

/// Read a whole file.
std::string slurp(const std::string& path);

/// Why @a document fails the JSON Schema in the source tree's @a schemaFile (libvxf's
/// JsonSchema message), or empty when it passes.
std::string schemaErrors(const nlohmann::json& document, const std::string& schemaFile);

/// Write a whole file.
void spit(const std::string& path, const std::string& text);

/// A grey material with the given absorption and scattering (1/world unit).
vxf::Material greyMaterial(double sigmaA, double sigmaS);

/// A grey material of extinction @a sigmaT and single-scattering @a albedo.
vxf::Material albedoMaterial(double sigmaT, double albedo);

/// A constant fluence @a phi named @a name over @a set's medium (its `density`) and, as the
/// light stage does, one voxel beyond it.
void putConstantFluence(vxf::VoxelSet& set, const std::string& name, double phi);

/// A homogeneous sphere of radius 1 (voxel size 1/@a cells) of material @a m: `density` 1 at
/// the voxels whose centre lies inside, `direct` = @a phi0 there and `scatter_source` =
/// σs'·phi0/4π (σs' = (1 − g)·σs, the transport's, Phase.h), as the light stage would write
/// for uniform light.
vxf::VoxelSet uniformSphere(const vxf::Material& m, double phi0, int cells = 16);

/// Put a `surface` into @a set: the level set of a sphere of @a radius about the origin on the
/// set's voxels (voxel size 1/@a cells, as uniformSphere's), a sharp boundary for its medium.
void putSphereSurface(vxf::VoxelSet& set, double radius, int cells);

/// Whether two grids are identical: type, class, background, transform, and every stored
/// value and active state (tiles compared voxel by voxel, so pruning does not matter).
/// On a difference, @a why says where.
bool identicalGrids(const openvdb::GridBase& a, const openvdb::GridBase& b, std::string* why = nullptr);

} // namespace vxf::test
