#include <vxf/view/ViewSession.h>

#include <vxf/core/GridRoles.h>
#include <vxf/core/GridStats.h>
#include <vxf/io/AtomicFile.h>
#include <vxf/io/VoxelSetFile.h>
#include <vxf/pipeline/Operators.h>

#include <openvdb/tools/GridTransformer.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <unordered_map>

namespace vxf::view {

namespace {

namespace fs = std::filesystem;

/// Export paths: a file name's limit on Linux file systems, and a bound on the whole path.
constexpr std::size_t kMaxNameBytes = 255, kMaxExportPathBytes = 1024;
/// The pipeline written beside a whole export, NAME.pipeline.json.
constexpr const char* kPipelineSuffix = ".pipeline.json";

/// @a text for a message: control bytes as \xNN, cut to 80 bytes.
std::string printable(const std::string& text)
{
    std::string out;
    for (const unsigned char c : text.substr(0, 80))
        out += c < 0x20 || c == 0x7f ? fmt::format("\\x{:02x}", unsigned(c)) : std::string(1, char(c));
    return text.size() > 80 ? out + "…" : out;
}

/// The largest slice sent (cells): a 4096² plane of floats is 64 MiB, more than a page draws.
constexpr std::int64_t kMaxSliceCells = std::int64_t(2048) * 2048;

/// Call @a fn with @a grid as its own type when it holds float or Vec3 values (any precision);
/// vxf::UsageError naming it for other types. One dispatch per call, not per voxel.
template <typename Fn>
void withTypedGrid(const openvdb::GridBase& grid, const std::string& name, Fn&& fn)
{
    if (const auto* g = dynamic_cast<const openvdb::FloatGrid*>(&grid)) return fn(*g);
    if (const auto* g = dynamic_cast<const openvdb::DoubleGrid*>(&grid)) return fn(*g);
    if (const auto* g = dynamic_cast<const openvdb::Vec3SGrid*>(&grid)) return fn(*g);
    if (const auto* g = dynamic_cast<const openvdb::Vec3DGrid*>(&grid)) return fn(*g);
    throw UsageError(fmt::format("grid '{}' holds {} values: the view shows float and vec3 grids", name, grid.valueType()));
}

/// A value of a float or Vec3 grid as 1 or 3 floats in @a out; returns the channels.
inline int toFloats(double v, float* out)
{
    out[0] = float(v);
    return 1;
}
template <typename T>
int toFloats(const openvdb::math::Vec3<T>& v, float* out)
{
    for (int c = 0; c < 3; ++c) out[c] = float(v[c]);
    return 3;
}

/// Visit the active values of a float or Vec3 grid as floats: @a fn(box, values, channels) →
/// false to stop, box one voxel or an active tile.
template <typename Fn>
void forEachActive(const openvdb::GridBase& grid, const std::string& name, Fn&& fn)
{
    withTypedGrid(grid, name, [&](const auto& typed) {
        float v[3];
        for (auto it = typed.cbeginValueOn(); it; ++it) {
            const int channels = toFloats(*it, v);
            if (!fn(it.getBoundingBox(), v, channels)) return;
        }
    });
}

int channelsOf(const openvdb::GridBase& grid)
{
    if (grid.isType<openvdb::Vec3SGrid>() || grid.isType<openvdb::Vec3DGrid>()) return 3;
    if (grid.isType<openvdb::FloatGrid>() || grid.isType<openvdb::DoubleGrid>()) return 1;
    return 0;
}

VoxelSet deepCopy(const VoxelSet& set)
{
    VoxelSet copy(set.transformPtr());
    for (const auto& grid : set.grids()) copy.putAsIs(grid->deepCopyGrid());
    copy.metadata() = set.metadata();
    copy.setPath(set.path());
    return copy;
}

} // namespace

const std::vector<std::string>& ViewSession::editOperators()
{
    static const std::vector<std::string> names = {"add", "sub", "mul", "div", "pow", "blend", "blur", "blur_special", "normalize",
        "denormalize", "gradient", "remove", "include", "select", "edit", "diff", "apply_diff", "split", "merge", "rename", "copy",
        "delete", "paint", "noise"};
    return names;
}

ViewSession::ViewSession(const std::string& path)
    : mPath(fs::absolute(path).lexically_normal().string())
    , mFolder(fs::path(mPath).parent_path().string())
    , mOriginal(readVoxelSet(path))
    , mCurrent(deepCopy(mOriginal))
{
}

openvdb::GridBase::ConstPtr ViewSession::gridNamed(const std::string& name) const
{
    auto grid = mCurrent.find(name);
    if (!grid) {
        std::string names;
        for (const auto& g : mCurrent.grids()) names += (names.empty() ? "" : ", ") + g->getName();
        throw UsageError(fmt::format("no grid '{}' in {} (it has: {})", name, mPath, names));
    }
    return grid;
}

nlohmann::json ViewSession::describe() const
{
    std::lock_guard<std::mutex> lock(mMutex);
    nlohmann::json grids = nlohmann::json::array();
    for (const auto& grid : mCurrent.grids()) {
        const GridStats stats = gridStats(*grid);
        nlohmann::json g{{"name", grid->getName()}, {"type", grid->valueType()},
            {"class", openvdb::GridBase::gridClassToString(grid->getGridClass())}, {"active_voxels", stats.activeVoxels},
            {"channels", channelsOf(*grid)}, {"voxel_size", grid->voxelSize()[0]}};
        if (!stats.activeBBox.empty()) {
            const openvdb::BBoxd world = grid->transform().indexToWorld(stats.activeBBox);
            g["index_min"] = {stats.activeBBox.min().x(), stats.activeBBox.min().y(), stats.activeBBox.min().z()};
            g["index_max"] = {stats.activeBBox.max().x(), stats.activeBBox.max().y(), stats.activeBBox.max().z()};
            g["world_min"] = {world.min().x(), world.min().y(), world.min().z()};
            g["world_max"] = {world.max().x(), world.max().y(), world.max().z()};
        }
        grids.push_back(std::move(g));
    }
    // Shown first: the light's result where there is one, else the first float or vec3 grid.
    std::string shown;
    for (const char* name : {grids::kScatter, grids::kIllumination, grids::kDirect, grids::kDensity}) {
        const auto grid = mCurrent.find(name);
        if (shown.empty() && grid && channelsOf(*grid) > 0) shown = name;
    }
    for (const auto& grid : mCurrent.grids()) {
        if (shown.empty() && channelsOf(*grid) > 0) shown = grid->getName();
    }
    // The up axis the file's writer uses: Houdini's is Y; Blender's and vxf's scenes Z.
    const auto creator = mOriginal.metadata().getMetadata<openvdb::StringMetadata>("creator");
    const std::string up = creator && creator->value().find("Houdini") != std::string::npos ? "y" : "z";
    return {{"file", mPath}, {"grids", grids}, {"steps", stepsLocked()}, {"redo", mRedo.size()}, {"operators", editOperators()},
        {"up_axis", up}, {"default_grid", shown.empty() ? nlohmann::json(nullptr) : nlohmann::json(shown)}};
}

nlohmann::json ViewSession::steps() const
{
    std::lock_guard<std::mutex> lock(mMutex);
    return stepsLocked();
}

nlohmann::json ViewSession::stepsLocked() const
{
    nlohmann::json steps = nlohmann::json::array();
    for (const Step& s : mSteps) {
        steps.push_back({{"op", s.op}, {"params", s.params}, {"enabled", s.enabled}, {"refreshes", s.refreshes}});
    }
    return steps;
}

PointCloud ViewSession::points(const std::string& name, std::size_t budget) const
{
    std::lock_guard<std::mutex> lock(mMutex);
    const auto grid = gridNamed(name);
    budget = std::max<std::size_t>(budget, 1);
    PointCloud cloud;
    cloud.channels = channelsOf(*grid);
    if (cloud.channels == 0) withTypedGrid(*grid, name, [](const auto&) {}); // the error
    cloud.activeVoxels = gridStats(*grid).activeVoxels;

    // The smallest cells that fit the budget (a tile counts as the cells it covers).
    struct Cell
    {
        double weight = 0.0;
        openvdb::Vec3d centre{0.0};
        double value[3] = {0.0, 0.0, 0.0};
    };
    std::unordered_map<openvdb::Coord, Cell> cells;
    const openvdb::CoordBBox bounds = gridStats(*grid).activeBBox;
    const openvdb::Coord corner = bounds.empty() ? openvdb::Coord(0) : bounds.min();
    // Cells of 1, 2, 3, 4, 6, 8, 12, 16… voxels a side (about 3.4 times fewer points a step, not
    // 8), up to one cell over the whole bounds.
    const int widest = std::max({bounds.dim().x(), bounds.dim().y(), bounds.dim().z(), 1});
    for (int step = 0;; ++step) {
        const int size = step == 0 ? 1 : ((step % 2 == 1 ? 2 : 3) << ((step - 1) / 2));
        cells.clear();
        bool over = false;
        forEachActive(*grid, name, [&](const openvdb::CoordBBox& box, const float* v, int channels) {
            for (int c = 0; c < channels; ++c) {
                if (!std::isfinite(v[c])) return true; // a NaN or inf voxel is not drawn
            }
            // Cells from the active bounds' corner (so that one cell holds them all at the top);
            // a tile wider than a cell adds itself to every cell it covers.
            const openvdb::Coord a = box.min() - corner, b = box.max() - corner;
            for (int x = a.x() / size; x <= b.x() / size && !over; ++x) {
                for (int y = a.y() / size; y <= b.y() / size && !over; ++y) {
                    for (int z = a.z() / size; z <= b.z() / size; ++z) {
                        const openvdb::Coord first = corner.offsetBy(x * size, y * size, z * size);
                        const openvdb::CoordBBox part(openvdb::Coord::maxComponent(box.min(), first),
                            openvdb::Coord::minComponent(box.max(), first.offsetBy(size - 1)));
                        const double w = double(part.volume());
                        Cell& cell = cells[openvdb::Coord(x, y, z)];
                        cell.weight += w;
                        cell.centre += w * part.getCenter();
                        for (int c = 0; c < channels; ++c) cell.value[c] += w * v[c];
                        if (cells.size() > budget) {
                            over = true;
                            break;
                        }
                    }
                }
            }
            return !over; // over the budget: this size is done with
        });
        if (!over || size >= widest) {
            cloud.cellVoxels = size;
            break;
        }
    }
    // In a fixed order (by cell), so that the same grid gives the same points.
    std::vector<std::pair<openvdb::Coord, Cell>> sorted(cells.begin(), cells.end());
    std::sort(sorted.begin(), sorted.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
    const openvdb::math::Transform& xform = grid->transform();
    cloud.cellSize = grid->voxelSize()[0] * double(cloud.cellVoxels);
    cloud.positions.reserve(sorted.size() * 3);
    cloud.values.reserve(sorted.size() * std::size_t(cloud.channels));
    double lo = std::numeric_limits<double>::max(), hi = -lo;
    for (const auto& [key, cell] : sorted) {
        const openvdb::Vec3d world = xform.indexToWorld(cell.centre / cell.weight);
        for (int a = 0; a < 3; ++a) cloud.positions.push_back(float(world[a]));
        for (int c = 0; c < cloud.channels; ++c) {
            const double v = cell.value[c] / cell.weight;
            cloud.values.push_back(float(v));
            lo = std::min(lo, v);
            hi = std::max(hi, v);
        }
    }
    if (lo <= hi) {
        cloud.minValue = lo;
        cloud.maxValue = hi;
    }
    return cloud;
}

VolumeBrick ViewSession::brick(const std::string& name, std::size_t maxCells) const
{
    std::lock_guard<std::mutex> lock(mMutex);
    const auto grid = gridNamed(name);
    VolumeBrick brick;
    brick.channels = channelsOf(*grid);
    if (brick.channels == 0) withTypedGrid(*grid, name, [](const auto&) {}); // the error
    const openvdb::CoordBBox bounds = gridStats(*grid).activeBBox;
    if (bounds.empty()) return brick;
    maxCells = std::max<std::size_t>(maxCells, 1);
    const openvdb::Coord size = bounds.dim();
    const auto cellsOf = [&](int k) {
        return std::size_t((size.x() + k - 1) / k) * std::size_t((size.y() + k - 1) / k) * std::size_t((size.z() + k - 1) / k);
    };
    int k = std::max(1, int(std::cbrt(double(size.x()) * size.y() * size.z() / double(maxCells))));
    while (k > 1 && cellsOf(k - 1) <= maxCells) --k;
    while (cellsOf(k) > maxCells) ++k;
    brick.cellVoxels = k;
    for (int a = 0; a < 3; ++a) brick.dims[a] = (size[a] + k - 1) / k;
    const std::size_t cells = cellsOf(k), stride = std::size_t(brick.channels) + 1;
    std::vector<double> sums(cells * stride, 0.0);
    const openvdb::Coord corner = bounds.min();
    const auto cellIndex = [&](int x, int y, int z) {
        return (std::size_t(z) * std::size_t(brick.dims[1]) + std::size_t(y)) * std::size_t(brick.dims[0]) + std::size_t(x);
    };
    forEachActive(*grid, name, [&](const openvdb::CoordBBox& box, const float* v, int channels) {
        for (int c = 0; c < channels; ++c) {
            if (!std::isfinite(v[c])) return true; // a NaN or inf voxel is not drawn
        }
        const openvdb::Coord a = box.min() - corner, b = box.max() - corner;
        for (int z = a.z() / k; z <= b.z() / k; ++z) {
            for (int y = a.y() / k; y <= b.y() / k; ++y) {
                for (int x = a.x() / k; x <= b.x() / k; ++x) {
                    const openvdb::Coord first = corner.offsetBy(x * k, y * k, z * k);
                    const openvdb::CoordBBox part(
                        openvdb::Coord::maxComponent(box.min(), first), openvdb::Coord::minComponent(box.max(), first.offsetBy(k - 1)));
                    const double w = double(part.volume());
                    double* cell = &sums[cellIndex(x, y, z) * stride];
                    for (int c = 0; c < channels; ++c) cell[c] += w * v[c];
                    cell[channels] += w;
                }
            }
        }
        return true;
    });
    brick.values.resize(cells * stride);
    double lo = std::numeric_limits<double>::max(), hi = -lo;
    const double perCell = double(k) * k * k;
    for (std::size_t i = 0; i < cells; ++i) {
        const double* cell = &sums[i * stride];
        const double active = cell[brick.channels];
        for (int c = 0; c < brick.channels; ++c) {
            const double v = active > 0.0 ? cell[c] / active : 0.0;
            brick.values[i * stride + std::size_t(c)] = float(v);
            if (active > 0.0) {
                lo = std::min(lo, v);
                hi = std::max(hi, v);
            }
        }
        brick.values[i * stride + std::size_t(brick.channels)] = float(active / perCell);
    }
    if (lo <= hi) {
        brick.minValue = lo;
        brick.maxValue = hi;
    }
    const openvdb::math::Transform& xform = grid->transform();
    const openvdb::Vec3d low = xform.indexToWorld(corner.asVec3d() - openvdb::Vec3d(0.5)),
                         high = xform.indexToWorld(
                             corner.asVec3d() + openvdb::Vec3d(brick.dims[0], brick.dims[1], brick.dims[2]) * k - openvdb::Vec3d(0.5));
    brick.worldMin = openvdb::Vec3d(std::min(low[0], high[0]), std::min(low[1], high[1]), std::min(low[2], high[2]));
    brick.worldMax = openvdb::Vec3d(std::max(low[0], high[0]), std::max(low[1], high[1]), std::max(low[2], high[2]));
    return brick;
}

Slice ViewSession::slice(const std::string& name, int axis, int index) const
{
    std::lock_guard<std::mutex> lock(mMutex);
    const auto grid = gridNamed(name);
    if (axis < 0 || axis > 2) throw UsageError(fmt::format("slice axis {} is not 0, 1 or 2 (x, y, z)", axis));
    Slice s;
    s.axis = axis;
    s.channels = channelsOf(*grid);
    if (s.channels == 0) withTypedGrid(*grid, name, [](const auto&) {}); // the error
    const openvdb::CoordBBox bounds = gridStats(*grid).activeBBox;
    if (bounds.empty()) return s;
    const int u = axis == 0 ? 1 : 0, v = axis == 2 ? 1 : 2;
    s.index = std::clamp(index, bounds.min()[axis], bounds.max()[axis]);
    s.width = bounds.dim()[u];
    s.height = bounds.dim()[v];
    if (std::int64_t(s.width) * s.height > kMaxSliceCells) {
        throw UsageError(fmt::format(
            "grid '{}' is {} x {} voxels across axis {}: over the view's {} cells a slice", name, s.width, s.height, axis, kMaxSliceCells));
    }
    s.origin = bounds.min();
    s.origin[axis] = s.index;
    s.values.assign(std::size_t(s.width) * std::size_t(s.height) * std::size_t(s.channels), std::nanf(""));
    withTypedGrid(*grid, name, [&](const auto& typed) {
        auto accessor = typed.getConstAccessor();
        typename std::decay_t<decltype(typed)>::ValueType value;
        for (int j = 0; j < s.height; ++j) {
            for (int i = 0; i < s.width; ++i) {
                openvdb::Coord ijk = s.origin;
                ijk[u] += i;
                ijk[v] += j;
                if (!accessor.probeValue(ijk, value)) continue;
                toFloats(value, &s.values[(std::size_t(j) * std::size_t(s.width) + std::size_t(i)) * std::size_t(s.channels)]);
            }
        }
    });
    return s;
}

SurfaceMesh ViewSession::surfaceMesh(std::size_t triangleBudget) const
{
    // Made without the lock from the grid as it is now (an edit of it copies it first), and kept
    // for that grid and budget: the page asks again after every edit.
    openvdb::FloatGrid::ConstPtr surface;
    {
        std::lock_guard<std::mutex> lock(mMutex);
        surface = openvdb::gridPtrCast<openvdb::FloatGrid>(mCurrent.find(grids::kSurface));
        if (mMeshCache && mMeshCache->surface == surface && mMeshCache->budget == triangleBudget) return mMeshCache->mesh;
    }
    SurfaceMesh mesh = meshOf(surface, triangleBudget);
    std::lock_guard<std::mutex> lock(mMutex);
    mMeshCache = MeshCache{surface, triangleBudget, mesh};
    return mesh;
}

SurfaceMesh ViewSession::meshOf(const openvdb::FloatGrid::ConstPtr& surface, std::size_t triangleBudget)
{
    SurfaceMesh mesh;
    if (!surface || surface->getGridClass() != openvdb::GRID_LEVEL_SET) return mesh;
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    const auto extract = [&](const openvdb::FloatGrid& levelSet) {
        points.clear();
        triangles.clear();
        quads.clear();
        openvdb::tools::volumeToMesh(levelSet, points, triangles, quads, 0.0, 0.5);
        return triangles.size() + 2 * quads.size();
    };
    // Over the budget: once more from the level set resampled to voxels k times larger (OpenVDB
    // rebuilds a level set when it resamples one), the triangles falling as k².
    const std::size_t full = extract(*surface);
    if (full > triangleBudget) {
        const double k = std::ceil(std::sqrt(double(full) / double(std::max<std::size_t>(triangleBudget, 1))));
        auto coarse = openvdb::FloatGrid::create(surface->background());
        coarse->setGridClass(openvdb::GRID_LEVEL_SET);
        coarse->setTransform(openvdb::math::Transform::createLinearTransform(surface->voxelSize()[0] * k));
        openvdb::tools::resampleToMatch<openvdb::tools::BoxSampler>(*surface, *coarse);
        extract(*coarse);
    }
    mesh.positions.reserve(points.size() * 3);
    for (const auto& p : points) mesh.positions.insert(mesh.positions.end(), {p[0], p[1], p[2]});
    // OpenVDB's faces wind clockwise seen from outside: reversed for the usual counter-clockwise front.
    for (const auto& t : triangles) mesh.triangles.insert(mesh.triangles.end(), {t[0], t[2], t[1]});
    for (const auto& q : quads) mesh.triangles.insert(mesh.triangles.end(), {q[0], q[2], q[1], q[0], q[3], q[2]});
    return mesh;
}

void ViewSession::checkEdit(const std::string& name, const nlohmann::json& params)
{
    const auto& allowed = editOperators();
    if (std::find(allowed.begin(), allowed.end(), name) == allowed.end()) {
        throw UsageError(fmt::format("the view applies the artist operators ({}), not '{}'", fmt::join(allowed, ", "), name));
    }
    if (!params.is_object()) throw UsageError(fmt::format("{}: params must be a JSON object", name));
    for (const char* key : {"with_file", "from_file"}) {
        if (params.contains(key)) throw UsageError(fmt::format("{}: the view edits one file; '{}' is not taken here", name, key));
    }
}

void ViewSession::run(VoxelSet& set, const std::string& name, const nlohmann::json& params, std::string* report, Interrupter* progress)
{
    const ops::Operator& op = findOperator(name);
    const ops::Args args = ops::checkArgs(op, params);
    ops::OpContext context{set, args, progress};
    const std::string r = op.run(context);
    if (report) *report = r;
}

namespace {

/// The grids an edit step writes, as its operator declares them (ops::gridUse).
std::set<std::string> writtenGrids(const std::string& op, const nlohmann::json& params)
{
    const ops::Operator& declared = findOperator(op);
    return ops::gridUse(declared, ops::checkArgs(declared, params)).writes;
}

/// Whether a step writing @a written makes `illumination` (direct + scatter) stale.
bool staleIllumination(const std::set<std::string>& written)
{
    return (written.count(grids::kDirect) || written.count(grids::kScatter)) && !written.count(grids::kIllumination);
}

/// The step that makes `illumination` again from `direct` and `scatter`, as the scatter stage does.
const nlohmann::json& illuminationRefresh()
{
    static const nlohmann::json params{{"grid", grids::kDirect}, {"with", grids::kScatter}, {"mode", "add"}, {"out", grids::kIllumination}};
    return params;
}

} // namespace

void ViewSession::runStep(VoxelSet& set, Step& step, std::string* report)
{
    step.refreshes.clear();
    if (!step.enabled) {
        if (report) *report = "switched off";
        return;
    }
    run(set, step.op, step.params, report);
    const std::set<std::string> written = writtenGrids(step.op, step.params);
    if (staleIllumination(written) && set.find(grids::kIllumination) && set.find(grids::kDirect) && set.find(grids::kScatter)) {
        run(set, "blend", illuminationRefresh(), nullptr);
        step.refreshes.push_back(grids::kIllumination);
        if (report) *report += fmt::format("; recomputed '{}' = {} + {}", grids::kIllumination, grids::kDirect, grids::kScatter);
    }
}

VoxelSet ViewSession::replay(std::vector<Step> steps) const
{
    VoxelSet set = deepCopy(mOriginal);
    for (Step& s : steps) runStep(set, s, nullptr);
    return set;
}

void ViewSession::advance(Step& step, std::string* report)
{
    // The state before: the set's grids as they are; those the step (and a refresh) may write
    // are replaced in mCurrent by copies first, so the operator leaves the kept ones alone.
    const VoxelSet before = mCurrent;
    if (step.enabled) {
        std::set<std::string> written = writtenGrids(step.op, step.params);
        if (staleIllumination(written)) written.insert(grids::kIllumination); // runStep recomputes it
        for (const std::string& name : written) {
            if (const openvdb::GridBase::Ptr grid = mCurrent.find(name)) mCurrent.putAsIs(grid->deepCopyGrid());
        }
    }
    try {
        runStep(mCurrent, step, report);
    } catch (...) {
        mCurrent = before;
        throw;
    }
    mBefore.push_back(before);
    if (mBefore.size() > kKeptStates) mBefore[mBefore.size() - kKeptStates - 1].reset();
}

void ViewSession::rebuildFrom(std::size_t first)
{
    // From the nearest kept state at or before step `first`, else the file as read; past the
    // kept states mCurrent is the state before `first` already.
    if (first < mBefore.size()) {
        std::size_t from = first;
        while (from > 0 && !mBefore[from]) --from;
        if (mBefore[from]) {
            mCurrent = *mBefore[from];
        } else {
            mCurrent = deepCopy(mOriginal);
        }
        mBefore.resize(from);
        first = from;
    }
    for (std::size_t i = first; i < mSteps.size(); ++i) advance(mSteps[i], nullptr);
}

namespace {

/// Voxels of @a after active where @a before is not, or of another value, and voxels of @a before
/// no longer active in @a after (tiles counted voxel by voxel).
template <typename GridT>
std::uint64_t changedVoxels(const GridT& before, const GridT& after)
{
    std::uint64_t changed = 0;
    const auto countAgainst = [&changed](const GridT& a, const GridT& b, bool compareValues) {
        auto other = b.getConstAccessor();
        for (auto it = a.cbeginValueOn(); it; ++it) {
            openvdb::CoordBBox box;
            it.getBoundingBox(box);
            for (auto c = box.begin(); c; ++c) {
                if (!other.isValueOn(*c) || (compareValues && !openvdb::math::isExactlyEqual(other.getValue(*c), *it))) ++changed;
            }
        }
    };
    countAgainst(after, before, true);
    countAgainst(before, after, false);
    return changed;
}

/// "; changed N voxels of 'G'" for each grid of @a before (copies taken before the edit) as @a set holds it now.
std::string changedSummary(const std::map<std::string, openvdb::GridBase::Ptr>& before, const VoxelSet& set)
{
    std::string out;
    for (const auto& [name, old] : before) {
        const openvdb::GridBase::Ptr now = set.find(name);
        std::uint64_t changed = 0;
        if (!old || !now) {
            changed = old ? old->activeVoxelCount() : now ? now->activeVoxelCount() : 0;
        } else if (auto a = openvdb::gridPtrCast<openvdb::Vec3SGrid>(old)) {
            changed = changedVoxels(*a, *openvdb::gridPtrCast<openvdb::Vec3SGrid>(now));
        } else if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(old)) {
            changed = changedVoxels(*f, *openvdb::gridPtrCast<openvdb::FloatGrid>(now));
        } else if (auto m = openvdb::gridPtrCast<openvdb::BoolGrid>(old)) {
            changed = changedVoxels(*m, *openvdb::gridPtrCast<openvdb::BoolGrid>(now));
        } else {
            continue; // a grid type no edit writes
        }
        out += fmt::format("; changed {} voxels of '{}'", changed, name);
    }
    return out;
}

} // namespace

std::string ViewSession::apply(const std::string& op, const nlohmann::json& params)
{
    std::lock_guard<std::mutex> lock(mMutex);
    checkEdit(op, params);
    // The grids the step writes, as they were (advance keeps them): the report says how many
    // voxels it changed.
    Step step{op, params, true, {}};
    std::string report;
    advance(step, &report);
    std::map<std::string, openvdb::GridBase::Ptr> before;
    for (const std::string& name : writtenGrids(op, params)) before[name] = mBefore.back()->find(name);
    mSteps.push_back(step);
    mRedo.clear();
    return report + changedSummary(before, mCurrent);
}

bool ViewSession::undo()
{
    std::lock_guard<std::mutex> lock(mMutex);
    if (mSteps.empty()) return false;
    mRedo.push_back(mSteps.back());
    mSteps.pop_back();
    if (mBefore.back()) {
        mCurrent = *mBefore.back();
        mBefore.pop_back();
    } else {
        rebuildFrom(mSteps.size());
    }
    return true;
}

bool ViewSession::redo()
{
    std::lock_guard<std::mutex> lock(mMutex);
    if (mRedo.empty()) return false;
    Step step = mRedo.back();
    advance(step, nullptr);
    mSteps.push_back(step);
    mRedo.pop_back();
    return true;
}

std::size_t ViewSession::redoable() const
{
    std::lock_guard<std::mutex> lock(mMutex);
    return mRedo.size();
}

void ViewSession::setSteps(const nlohmann::json& list)
{
    std::lock_guard<std::mutex> lock(mMutex);
    if (!list.is_array()) throw UsageError("steps: expected a JSON array of {\"op\", \"params\", \"enabled\"}");
    std::vector<Step> steps;
    for (std::size_t i = 0; i < list.size(); ++i) {
        const nlohmann::json& s = list[i];
        const auto refuse = [&](const std::string& why) { throw UsageError(fmt::format("step {}: {}", i + 1, why)); };
        if (!s.is_object() || !s.contains("op") || !s["op"].is_string()) refuse("expected {\"op\": NAME, \"params\": {…}}");
        if (s.contains("enabled") && !s["enabled"].is_boolean()) refuse("'enabled' must be true or false");
        Step step{s["op"].get<std::string>(), s.value("params", nlohmann::json::object()), s.value("enabled", true), {}};
        try {
            checkEdit(step.op, step.params);
            if (step.enabled) writtenGrids(step.op, step.params); // the parameters checked as the operator checks them
        } catch (const Error& e) {
            refuse(e.what());
        }
        steps.push_back(std::move(step));
    }
    std::size_t first = 0;
    while (first < steps.size() && first < mSteps.size() && steps[first].op == mSteps[first].op &&
        steps[first].params == mSteps[first].params && steps[first].enabled == mSteps[first].enabled)
        ++first;
    if (first == steps.size() && first == mSteps.size()) return; // the same history
    for (std::size_t i = first; i < steps.size(); ++i) steps[i].refreshes.clear();
    std::vector<Step> oldSteps = mSteps;
    std::vector<std::optional<VoxelSet>> oldBefore = mBefore;
    const VoxelSet oldCurrent = mCurrent;
    mSteps = std::move(steps);
    try {
        rebuildFrom(first);
    } catch (const Error& e) {
        // Which step failed: the first whose state was not reached.
        const std::size_t failed = mBefore.size() + 1;
        mSteps = std::move(oldSteps);
        mBefore = std::move(oldBefore);
        mCurrent = oldCurrent;
        throw UsageError(fmt::format("step {}: {}", failed, e.what()));
    }
    mRedo.clear();
}

nlohmann::json ViewSession::pipeline(const std::string& output) const
{
    std::lock_guard<std::mutex> lock(mMutex);
    return pipelineLocked(output);
}

nlohmann::json ViewSession::pipelineLocked(const std::string& output) const
{
    nlohmann::json nodes{{"source", {{"file", mPath}}}};
    std::string last = "source";
    for (std::size_t i = 0; i < mSteps.size(); ++i) {
        if (!mSteps[i].enabled) continue;
        const std::string node = fmt::format("step{}_{}", i + 1, mSteps[i].op);
        nodes[node] = {{"op", mSteps[i].op}, {"input", last}, {"params", mSteps[i].params}};
        last = node;
        for (const std::string& refreshed : mSteps[i].refreshes) { // the derived grid made again, as the session did
            const std::string again = fmt::format("step{}_{}", i + 1, refreshed);
            nodes[again] = {{"op", "blend"}, {"input", last}, {"params", illuminationRefresh()}};
            last = again;
        }
    }
    return {{"nodes", nodes}, {"outputs", {{last, output}}}};
}

ViewSession::Rendered ViewSession::render(
    const std::string& scenePath, int width, int height, const std::string& folder, Interrupter* progress)
{
    const auto start = std::chrono::steady_clock::now();
    // What to render, taken under the lock and rendered without it (edits, reads and exports go
    // on meanwhile): the steps, the current set (its grids shared; a later edit copies what it
    // writes) and the kept scatter.
    std::vector<Step> steps;
    VoxelSet current, scattered;
    std::string scatteredFor;
    {
        std::lock_guard<std::mutex> lock(mMutex);
        steps = mSteps;
        current = mCurrent;
        scattered = mScattered;
        scatteredFor = mScatteredFor;
    }
    Rendered result;
    // The recorded steps in order: the scatter stage re-runs after the last step that wrote what
    // it reads, and the steps after that one apply to its result (a hue edit of `scatter` after
    // an edit of `density` shows in the render).
    static const std::set<std::string> upstream = [] {
        const ops::Operator& stage = findOperator("scatter");
        return ops::gridUse(stage, ops::checkArgs(stage, nlohmann::json::object())).reads;
    }();
    std::size_t rescatterAfter = 0; // steps [0, rescatterAfter) come before the scatter stage re-runs
    for (std::size_t i = 0; i < steps.size(); ++i) {
        if (!steps[i].enabled) continue;
        for (const std::string& g : writtenGrids(steps[i].op, steps[i].params)) {
            if (upstream.count(g)) rescatterAfter = i + 1;
        }
    }
    VoxelSet set = current;
    if (rescatterAfter > 0 && current.find(grids::kScatter)) {
        nlohmann::json before = nlohmann::json::array();
        for (std::size_t i = 0; i < rescatterAfter; ++i) {
            if (steps[i].enabled) before.push_back({steps[i].op, steps[i].params});
        }
        if (scatteredFor != before.dump()) {
            // The file's own scatter parameters where it recorded them (`vxf scatter`), else sweeps.
            nlohmann::json params = nlohmann::json::object();
            const nlohmann::json recorded = nlohmann::json::parse(mOriginal.paramsJson(), nullptr, false);
            if (mOriginal.stage() == "scatter" && recorded.is_object()) {
                for (const ops::Param& p : findOperator("scatter").params) {
                    if (recorded.contains(p.name) && p.name != "keep_passes" && p.name != "from_pass") params[p.name] = recorded[p.name];
                }
                if (recorded.value("no_accelerate", false) == true) params["accelerate"] = false; // written before the knob table
            }
            if (params.empty()) params = {{"kernel", "sweep"}};
            const VoxelSet edited = replay(std::vector<Step>(steps.begin(), steps.begin() + std::ptrdiff_t(rescatterAfter)));
            scattered = deepCopy(edited);
            try {
                run(scattered, "scatter", params, nullptr, progress);
            } catch (const UsageError&) { // recorded values this version no longer takes
                scattered = deepCopy(edited);
                run(scattered, "scatter", {{"kernel", "sweep"}}, nullptr, progress);
            }
            {
                std::lock_guard<std::mutex> lock(mMutex);
                mScattered = scattered;
                mScatteredFor = before.dump();
            }
            result.ran.push_back("scatter");
        } else {
            result.ran.push_back("scatter (kept from the last render)");
        }
        // Later steps edit a copy (the kept scatter stays as the stage made it); none: read as it is.
        set = rescatterAfter < steps.size() ? deepCopy(scattered) : scattered;
        for (std::size_t i = rescatterAfter; i < steps.size(); ++i) runStep(set, steps[i], nullptr);
        if (rescatterAfter < steps.size()) result.ran.push_back(fmt::format("{} later steps", steps.size() - rescatterAfter));
    }
    fs::create_directories(folder);
    result.png = (fs::path(folder) / "view.png").string();
    run(set, "render",
        {{"scene", scenePath}, {"image", (fs::path(folder) / "view.exr").string()}, {"png", result.png}, {"width", width},
            {"height", height}},
        nullptr, progress);
    result.ran.push_back("render");
    result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return result;
}

std::string ViewSession::resolveInside(const std::string& relativePath) const
{
    const auto refuse = [&](const std::string& why) {
        throw UsageError(fmt::format("export path '{}': {}", printable(relativePath), why));
    };
    // Bytes a file name cannot hold or a shell would hide: a NUL ends the name the system sees
    // ("notes.json\0.vdb" is notes.json), the others hide in listings and logs.
    for (const unsigned char c : relativePath) {
        if (c < 0x20 || c == 0x7f) refuse(fmt::format("holds the control character 0x{:02x}", unsigned(c)));
    }
    const fs::path given(relativePath);
    if (relativePath.empty() || given.is_absolute()) refuse(fmt::format("give a path relative to {} (the served file's folder)", mFolder));
    if (relativePath.size() > kMaxExportPathBytes)
        refuse(fmt::format("{} bytes long; at most {}", relativePath.size(), kMaxExportPathBytes));
    for (const auto& part : given) {
        if (part == "..") refuse(fmt::format("'..' would leave {}", mFolder));
        if (part == "~") refuse("'~' is not your home here: give a path relative to the served file's folder");
        if (part.string().size() > kMaxNameBytes)
            refuse(fmt::format("a name of {} bytes; at most {}", part.string().size(), kMaxNameBytes));
    }
    if (given.extension() != ".vdb") refuse("must end in .vdb");
    // NAME.pipeline.json is written beside a whole export: it must be a valid name too.
    if (given.stem().string().size() + std::strlen(kPipelineSuffix) > kMaxNameBytes) {
        refuse(fmt::format("the name leaves no room for its {} (at most {} bytes before .vdb)", kPipelineSuffix,
            kMaxNameBytes - std::strlen(kPipelineSuffix)));
    }
    // Real paths: a symbolic link inside the folder may point out of it; exports create no folder.
    std::error_code error;
    const fs::path folder = fs::canonical(mFolder, error);
    if (error) refuse(fmt::format("the served file's folder {} cannot be resolved ({})", mFolder, error.message()));
    const fs::path parent = (fs::path(mFolder) / given).parent_path();
    if (!fs::is_directory(parent, error)) {
        refuse(fmt::format("no folder '{}' in {} (exports create no folders)", given.parent_path().string(), mFolder));
    }
    const fs::path realParent = fs::canonical(parent, error);
    if (error) refuse(fmt::format("its folder cannot be resolved ({})", error.message()));
    const auto [end, rest] = std::mismatch(folder.begin(), folder.end(), realParent.begin(), realParent.end());
    if (end != folder.end()) refuse(fmt::format("its folder is {}, outside {} (through a symbolic link)", realParent.string(), mFolder));
    const fs::path target = realParent / given.filename();
    if (fs::is_directory(target, error)) refuse("is a folder");
    if (fs::exists(target, error) && fs::equivalent(target, mPath, error)) refuse("is the served file itself: export beside it");
    return target.string();
}

std::string ViewSession::exportTo(
    const std::string& relativePath, ExportMode mode, const std::string& grid, int smooth, const std::vector<std::string>& keep)
{
    const std::string path = resolveInside(relativePath);
    nlohmann::json graph;
    VoxelSet out;
    {
        std::lock_guard<std::mutex> lock(mMutex);
        if (mode == ExportMode::Whole) {
            // The grids kept; the pipeline deletes the others at its end, as the export does.
            for (const std::string& name : keep) gridNamed(name);
            out = mCurrent;
            graph = pipelineLocked(path);
            std::string last = graph["outputs"].begin().key();
            for (const auto& g : mCurrent.grids()) {
                if (keep.empty() || std::find(keep.begin(), keep.end(), g->getName()) != keep.end()) continue;
                out.remove(g->getName());
                const std::string node = fmt::format("export_delete_{}", graph["nodes"].size());
                graph["nodes"][node] = {{"op", "delete"}, {"input", last}, {"params", {{"grid", g->getName()}}}};
                last = node;
            }
            graph["outputs"] = {{last, path}};
        } else {
            if (!mCurrent.find(grid)) throw UsageError(fmt::format("export: no grid '{}' in the edited set", grid));
            if (!mOriginal.find(grid)) throw UsageError(fmt::format("export: grid '{}' is new (not in {}): export it whole", grid, mPath));
            // The original with the edited grid beside it, then the same operators as `vxf op`.
            VoxelSet work = deepCopy(mOriginal);
            const std::string edited = grid + ":edited", difference = grid + "_diff";
            auto copy = mCurrent.find(grid)->deepCopyGrid();
            copy->setName(edited);
            work.putAsIs(copy);
            run(work, "diff", {{"grid", grid}, {"with", edited}, {"out", difference}}, nullptr);
            if (mode == ExportMode::Diff) {
                out = VoxelSet(work.transformPtr());
                out.putAsIs(work.find(difference));
            } else {
                run(work, "apply_diff", {{"grid", grid}, {"with", difference}, {"smooth", std::clamp(smooth, 0, 64)}}, nullptr);
                work.remove(edited);
                work.remove(difference);
                out = work;
            }
        }
    }
    out.setProvenance("view",
        nlohmann::json{{"file", mPath},
            {"export",
                mode == ExportMode::Whole      ? "whole"
                    : mode == ExportMode::Diff ? "diff"
                                               : "smoothed"},
            {"grid", grid}}
            .dump());
    writeVoxelSet(path, out);
    if (mode == ExportMode::Whole) {
        const std::string pipelinePath = (fs::path(path).parent_path() / (fs::path(path).stem().string() + kPipelineSuffix)).string();
        const std::string text = graph.dump(2) + "\n";
        writeAtomically(pipelinePath, [&](const std::string& tmp) {
            std::ofstream file(tmp, std::ios::binary);
            file << text;
            file.close();
            if (!file) throw Error(fmt::format("{}: cannot write", pipelinePath));
        });
    }
    return path;
}

} // namespace vxf::view
