// vxf — the state behind `vxf view`: one voxel set, its edits by the artist operators, undo, exports.
#pragma once

#include <vxf/core/Interrupter.h>
#include <vxf/core/VoxelSet.h>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

namespace vxf::view {

/// Points standing for a grid's active voxels, few enough to draw: each voxel where the grid has
/// at most the budget, else one point per cell of 2, 3, 4, 6, 8, 12… voxels a side (the mean of
/// the cell's active values at the mean of their centres, world space), the smallest that fits.
struct PointCloud
{
    int cellVoxels = 1; ///< a cell's side in voxels (1: one point per voxel)
    double cellSize = 0.0; ///< world size of a point's cell
    int channels = 1; ///< 1 (float grids) or 3 (Vec3 grids)
    std::vector<float> positions; ///< x, y, z per point
    std::vector<float> values; ///< `channels` per point
    double minValue = 0.0, maxValue = 0.0; ///< over every channel of the points (0, 0 when none)
    std::uint64_t activeVoxels = 0; ///< of the whole grid
};

/// An axis-aligned slice through a grid's active bounds: @a width x @a height values (index
/// space, row-major, rows along the second axis), NaN where no voxel is active.
struct Slice
{
    int axis = 2, index = 0;
    openvdb::Coord origin; ///< index of values[0]
    int width = 0, height = 0;
    int channels = 1;
    std::vector<float> values; ///< channels per cell
};

/// A grid as a dense brick of cells for the page's ray-marched view: cells of `cellVoxels`
/// voxels a side over its active bounds, each holding the mean of its active voxels' values and
/// the share of its voxels that are active (tiles counted voxel by voxel).
struct VolumeBrick
{
    int cellVoxels = 1;
    int dims[3] = {0, 0, 0}; ///< cells along x, y, z
    int channels = 1; ///< 1 (float grids) or 3 (Vec3 grids)
    /// World corners of the brick (its first cell's low corner, its last cell's high one): the
    /// grid's index box through its transform (a rotated transform is drawn axis-aligned).
    openvdb::Vec3d worldMin{0.0}, worldMax{0.0};
    std::vector<float> values; ///< channels + 1 (coverage) per cell, x fastest, then y, then z
    double minValue = 0.0, maxValue = 0.0; ///< over the active cells' channels (0, 0 when none)
};

/// A triangle mesh of the `surface` level set (OpenVDB's volumeToMesh), world space.
struct SurfaceMesh
{
    std::vector<float> positions; ///< x, y, z per vertex
    std::vector<std::uint32_t> triangles;
};

/// How an export writes the edited grid (the thesis's three exports).
enum class ExportMode {
    Whole, ///< the edited voxel set, every grid
    Diff, ///< the difference of the edited grid from the original (`vxf op diff`), alone
    Smoothed ///< the original set with that difference replayed, its edge blended (`apply_diff --smooth`)
};

/// One .vdb open for viewing and editing. Every edit is one operator of the registry (as
/// `vxf op` runs it, checked by ops::checkArgs) applied to the current set and recorded, so the
/// current set is always exactly what `vxf graph` makes of pipeline(). The record is a history:
/// steps can be undone and redone, switched off and on, removed and reordered (setSteps).
/// A step that changes `direct` or `scatter` in a set holding `illumination` (their sum, which
/// the scatter stage writes) recomputes it after it, said in its report and recorded in
/// pipeline() as a node of its own: no derived grid goes stale.
/// The state before each of the last kKeptStates steps is kept (the grids a step writes are
/// copied before it runs, the others shared), so undo and a history change near the end take
/// no replay; older states are replayed from the file as read. Thread-safe: every call takes
/// the session's lock.
class ViewSession
{
public:
    /// Read @a path (vxf::Error naming it when it cannot be read).
    explicit ViewSession(const std::string& path);

    const std::string& path() const { return mPath; }
    /// The folder exports may write into: the served file's.
    const std::string& folder() const { return mFolder; }

    /// The current set's grids: name, value type, class, channels, active voxels, index and
    /// world bounds, voxel size; the steps recorded; the operators apply() takes; the grid to
    /// show first (default_grid: scatter, illumination, direct or density, else the first float
    /// or vec3 grid; null when there is none).
    nlohmann::json describe() const;

    /// The recorded steps: [{"op", "params", "enabled", "refreshes"}…], oldest first
    /// ("refreshes": the grids recomputed after it, such as illumination).
    nlohmann::json steps() const;

    /// Points for @a grid (float or Vec3 of any precision; vxf::UsageError for other types or an
    /// unknown name) within @a budget points (≥ 1).
    PointCloud points(const std::string& grid, std::size_t budget) const;

    /// @a grid (float or Vec3) as a brick of at most @a maxCells cells (≥ 1), the smallest
    /// cells that fit; vxf::UsageError as points() gives.
    VolumeBrick brick(const std::string& grid, std::size_t maxCells) const;

    /// The slice of @a grid across @a axis (0, 1, 2) at index @a index (clamped into its bounds).
    Slice slice(const std::string& grid, int axis, int index) const;

    /// The `surface` grid's mesh (empty when the set has none) of at most about @a triangleBudget
    /// triangles (from a coarser level set where the grid's own gives more); kept until the grid
    /// or the budget changes.
    SurfaceMesh surfaceMesh(std::size_t triangleBudget) const;

    /// Apply operator @a op with @a params (a JSON object, as in a pipeline node) to the current
    /// set and record it; returns the operator's report. Only the artist operators that edit a
    /// set in place are allowed (not the pipeline stages, not those reading other files).
    /// Errors leave the set and the record unchanged.
    std::string apply(const std::string& op, const nlohmann::json& params);

    /// Drop the last recorded step (false when there is none), the set as it was before it;
    /// the step goes on the redo list.
    bool undo();

    /// Apply again the step undone last (false when there is none). An apply() or setSteps()
    /// empties the redo list.
    bool redo();

    /// How many undone steps redo() can apply again.
    std::size_t redoable() const;

    /// Replace the recorded steps by @a steps ([{"op", "params", "enabled"?}…]: the same steps
    /// switched off or on, removed or reordered, or others) and rebuild the set from the first
    /// one that differs. Each is checked as apply() checks it; on an error (vxf::UsageError
    /// naming the step) the session is left as it was.
    void setSteps(const nlohmann::json& steps);

    /// The recorded steps as a pipeline (schemas/pipeline.schema.json): the served file as the
    /// source node, one node per step, the last written to @a output (a path, stored as given).
    nlohmann::json pipeline(const std::string& output) const;

    /// Write @a mode's result for @a grid to @a relativePath, a .vdb path inside folder() (no
    /// absolute paths, no "..": vxf::UsageError), atomically; with Whole also the pipeline that
    /// makes it beside it (NAME.pipeline.json). @a smooth: voxels blended (Smoothed). With
    /// Whole, @a keep names the grids written (empty: every grid; an unknown name is an error),
    /// the pipeline deleting the others at its end. Returns the absolute path written.
    std::string exportTo(
        const std::string& relativePath, ExportMode mode, const std::string& grid, int smooth, const std::vector<std::string>& keep = {});

    /// What render() did: the stages it ran ("scatter", or the scatter kept from the last render;
    /// "render") and the PNG it wrote.
    struct Rendered
    {
        std::vector<std::string> ran;
        std::string png;
        double seconds = 0.0;
    };

    /// Render the edited set with @a scenePath's camera and lights (the `render` operator,
    /// @a width x @a height) into @a folder, first re-running the `scatter` operator where a
    /// recorded step edited a grid it reads (surface, density, direct, scatter_source, scatter_source_anisotropy) and the
    /// set holds a `scatter` to replace: with the parameters the file's scatter stage recorded,
    /// else accelerated sweeps. The re-scattered set is kept until the steps change, so renders
    /// of the same edits scatter once (as `vxf run`'s cache reuses unchanged stages). The set is
    /// taken under the lock and rendered without it: the other calls answer meanwhile (renders
    /// one at a time: the caller's to order). @a progress: the stages' progress (may be null).
    Rendered render(const std::string& scenePath, int width, int height, const std::string& folder, Interrupter* progress = nullptr);

    /// The operators apply() accepts.
    static const std::vector<std::string>& editOperators();

    /// How many of the latest states before a step are kept for undo and history changes.
    static constexpr std::size_t kKeptStates = 8;

private:
    struct Step
    {
        std::string op;
        nlohmann::json params;
        bool enabled = true;
        /// Set when the step runs: the derived grids it recomputed after it ("illumination").
        std::vector<std::string> refreshes;
    };
    /// Run @a step on @a set (nothing when it is switched off), then recompute what it made stale
    /// (Step::refreshes); the operator's report and what was recomputed in @a report.
    static void runStep(VoxelSet& set, Step& step, std::string* report);
    /// runStep on mCurrent, keeping the state before it (the grids it writes copied first).
    void advance(Step& step, std::string* report);
    /// mCurrent and the kept states for mSteps from step @a first on (its state before restored
    /// or replayed from the file as read); the lock held.
    void rebuildFrom(std::size_t first);
    /// The file as read with @a steps applied (their refreshes too), from a copy of mOriginal.
    VoxelSet replay(std::vector<Step> steps) const;
    /// vxf::UsageError unless @a op is one of editOperators() with @a params an object naming no other file.
    static void checkEdit(const std::string& op, const nlohmann::json& params);
    /// Operator @a op of the registry on @a set, its parameters checked as `vxf op` checks them.
    static void run(
        VoxelSet& set, const std::string& op, const nlohmann::json& params, std::string* report, Interrupter* progress = nullptr);
    /// The mesh of level set @a surface (none: empty) within @a triangleBudget.
    static SurfaceMesh meshOf(const openvdb::FloatGrid::ConstPtr& surface, std::size_t triangleBudget);
    openvdb::GridBase::ConstPtr gridNamed(const std::string& name) const;
    nlohmann::json stepsLocked() const; ///< steps(), the lock held
    nlohmann::json pipelineLocked(const std::string& output) const; ///< pipeline(), the lock held
    std::string resolveInside(const std::string& relativePath) const;

    std::string mPath, mFolder;
    VoxelSet mOriginal; ///< as read (never edited: each replay starts from deep copies)
    VoxelSet mCurrent;
    std::vector<Step> mSteps;
    std::vector<Step> mRedo; ///< undone steps, the last undone at the back
    /// mBefore[i]: the set before step i (null where no longer kept); as many as mSteps.
    std::vector<std::optional<VoxelSet>> mBefore;
    std::string mScatteredFor; ///< the steps (as JSON) mScattered was made for; "" none
    VoxelSet mScattered;
    struct MeshCache
    {
        openvdb::FloatGrid::ConstPtr surface; ///< the grid it was made from (kept alive: the key)
        std::size_t budget = 0;
        SurfaceMesh mesh;
    };
    mutable std::optional<MeshCache> mMeshCache;
    mutable std::mutex mMutex;
};

} // namespace vxf::view
