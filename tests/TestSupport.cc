#include "TestSupport.h"

#include <vxf/transport/Phase.h>

#include <vxf/core/Error.h>
#include <vxf/io/JsonDocument.h>

#include <fmt/format.h>
#include <openvdb/tools/LevelSetSphere.h>
#include <openvdb/tools/Morphology.h>

#include <cstdlib>
#include <fstream>
#include <random>
#include <sstream>

#include <sys/wait.h>

namespace vxf::test {

TempDir::TempDir()
{
    std::random_device rd;
    mPath = std::filesystem::temp_directory_path() / fmt::format("vxf-test-{:08x}{:08x}", rd(), rd());
    std::filesystem::create_directories(mPath);
}

TempDir::~TempDir()
{
    std::error_code ec;
    std::filesystem::remove_all(mPath, ec);
}

std::string slurp(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::stringstream buffer;
    buffer << in.rdbuf();
    return buffer.str();
}

std::string schemaErrors(const nlohmann::json& document, const std::string& schemaFile)
{
    const JsonSchema schema(nlohmann::json::parse(slurp(source(schemaFile))), schemaFile);
    try {
        schema.check(document, "document");
    } catch (const Error& e) {
        return e.what();
    }
    return {};
}

void spit(const std::string& path, const std::string& text)
{
    std::ofstream out(path, std::ios::binary);
    out << text;
}

RunResult run(const std::string& commandLine)
{
    TempDir io;
    const std::string out = io.path("out"), err = io.path("err");
    const int raw = std::system(fmt::format("{} >'{}' 2>'{}' </dev/null", commandLine, out, err).c_str());
    RunResult result;
    result.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : 128 + WTERMSIG(raw);
    result.out = slurp(out);
    result.err = slurp(err);
    return result;
}

vxf::Material greyMaterial(double sigmaA, double sigmaS)
{
    vxf::Material m;
    m.sigmaA = openvdb::Vec3d(sigmaA);
    m.sigmaS = openvdb::Vec3d(sigmaS);
    return m;
}

vxf::Material albedoMaterial(double sigmaT, double albedo) { return greyMaterial(sigmaT - albedo * sigmaT, albedo * sigmaT); }

std::string binary(const std::string& name) { return std::string(VXF_BINARY_DIR) + "/" + name; }

std::string source(const std::string& relative) { return std::string(VXF_SOURCE_DIR) + "/" + relative; }

namespace {

template <typename GridT>
bool identicalTyped(const GridT& a, const GridT& b, std::string* why)
{
    const auto say = [&](const std::string& text) {
        if (why) *why = text;
        return false;
    };
    if (!openvdb::math::isExactlyEqual(a.background(), b.background())) return say("backgrounds differ");
    // Active values voxel by voxel (tiles expanded: they are bounded by real content), inactive
    // leaf voxels one by one, inactive tiles by their value at the corner and centre (they span
    // up to 4096^3 voxels of background).
    auto accA = a.getConstAccessor();
    auto accB = b.getConstAccessor();
    for (int pass = 0; pass < 2; ++pass) {
        const GridT& one = pass == 0 ? a : b;
        auto& otherAcc = pass == 0 ? accB : accA;
        const auto differs = [&](const openvdb::Coord& ijk, const typename GridT::ValueType& value, bool on) {
            return !openvdb::math::isExactlyEqual(value, otherAcc.getValue(ijk)) || on != otherAcc.isValueOn(ijk);
        };
        for (auto it = one.cbeginValueOn(); it; ++it) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto ijk = box.begin(); ijk; ++ijk) {
                if (differs(*ijk, *it, true)) return say(fmt::format("voxel ({}, {}, {}) differs", (*ijk)[0], (*ijk)[1], (*ijk)[2]));
            }
        }
        for (auto leaf = one.tree().cbeginLeaf(); leaf; ++leaf) {
            for (auto it = leaf->cbeginValueOff(); it; ++it) {
                const openvdb::Coord ijk = it.getCoord();
                if (differs(ijk, *it, false)) return say(fmt::format("inactive voxel ({}, {}, {}) differs", ijk[0], ijk[1], ijk[2]));
            }
        }
        for (auto it = one.tree().cbeginValueOff(); it; ++it) {
            if (it.isVoxelValue()) continue;
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            if (differs(box.min(), *it, false) || differs(box.min().offsetBy(box.dim().x() / 2), *it, false)) {
                return say(fmt::format("inactive tile at ({}, {}, {}) differs", box.min()[0], box.min()[1], box.min()[2]));
            }
        }
    }
    return true;
}

} // namespace

bool identicalGrids(const openvdb::GridBase& a, const openvdb::GridBase& b, std::string* why)
{
    const auto say = [&](const std::string& text) {
        if (why) *why = text;
        return false;
    };
    if (a.type() != b.type()) return say("types differ: " + a.type() + " vs " + b.type());
    if (a.getGridClass() != b.getGridClass()) return say("classes differ");
    if (a.transform() != b.transform()) return say("transforms differ");
    if (a.activeVoxelCount() != b.activeVoxelCount()) {
        return say(fmt::format("active voxel counts differ: {} vs {}", a.activeVoxelCount(), b.activeVoxelCount()));
    }
    if (auto fa = dynamic_cast<const openvdb::FloatGrid*>(&a)) {
        return identicalTyped(*fa, static_cast<const openvdb::FloatGrid&>(b), why);
    }
    if (auto va = dynamic_cast<const openvdb::Vec3SGrid*>(&a)) {
        return identicalTyped(*va, static_cast<const openvdb::Vec3SGrid&>(b), why);
    }
    if (auto ba = dynamic_cast<const openvdb::BoolGrid*>(&a)) {
        return identicalTyped(*ba, static_cast<const openvdb::BoolGrid&>(b), why);
    }
    if (auto ia = dynamic_cast<const openvdb::Int32Grid*>(&a)) {
        return identicalTyped(*ia, static_cast<const openvdb::Int32Grid&>(b), why);
    }
    return say("unsupported grid type " + a.type());
}

void putConstantFluence(vxf::VoxelSet& set, const std::string& name, double phi)
{
    auto density = set.get<openvdb::FloatGrid>("density");
    auto grid = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    grid->setName(name);
    grid->setTransform(set.transformPtr());
    grid->tree().topologyUnion(density->tree());
    grid->tree().voxelizeActiveTiles();
    openvdb::tools::dilateActiveValues(grid->tree(), 1, openvdb::tools::NN_FACE_EDGE_VERTEX, openvdb::tools::IGNORE_TILES);
    for (auto it = grid->beginValueOn(); it; ++it) it.setValue(openvdb::Vec3f(float(phi)));
    set.put(grid);
}

void putSphereSurface(vxf::VoxelSet& set, double radius, int cells)
{
    auto surface = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(float(radius), openvdb::Vec3f(0.0f), 1.0f / float(cells), 3.0f);
    surface->setName("surface");
    set.put(surface);
}

vxf::VoxelSet uniformSphere(const vxf::Material& m, double phi0, int cells)
{
    const double dx = 1.0 / cells;
    vxf::VoxelSet set(openvdb::math::Transform::createLinearTransform(dx));
    auto density = openvdb::FloatGrid::create(0.0f);
    density->setName("density");
    density->setTransform(set.transformPtr());
    auto direct = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    direct->setName("direct");
    direct->setTransform(set.transformPtr());
    auto source = openvdb::Vec3SGrid::create(openvdb::Vec3f(0.0f));
    source->setName("scatter_source");
    source->setTransform(set.transformPtr());
    for (int i = -cells; i <= cells; ++i)
        for (int j = -cells; j <= cells; ++j)
            for (int k = -cells; k <= cells; ++k) {
                const openvdb::Coord c(i, j, k);
                if (c.asVec3d().length() * dx > 1.0) continue;
                density->tree().setValueOn(c, 1.0f);
                direct->tree().setValueOn(c, openvdb::Vec3f(float(phi0)));
                source->tree().setValueOn(c, openvdb::Vec3f(m.sigmaS * (vxf::reducedScatteringFactor(m.phaseG) * phi0 / (4.0 * M_PI))));
            }
    set.put(density);
    set.put(direct);
    set.put(source);
    return set;
}

} // namespace vxf::test
