#include "OperatorGroups.h"

#include <vxf/core/Error.h>
#include <vxf/io/VoxelSetFile.h>

#include <fmt/format.h>

namespace vxf::ops::detail {

using namespace params;

Param gridParam(const char* summary) { return text("grid", summary); }
Param outParam() { return text("out", "(optional) write the result as this grid instead of replacing the input"); }
Param withParam(const char* summary) { return text("with", summary); }
Param withFileParam() { return text("with_file", "(optional) take 'with' from this .vdb instead of the same file"); }

openvdb::GridBase::Ptr requireGrid(const VoxelSet& set, const std::string& op, const std::string& name)
{
    if (auto g = set.find(name)) return g;
    std::string names;
    for (const auto& g : set.grids()) names += (names.empty() ? "" : ", ") + g->getName();
    throw UsageError(fmt::format("{}: no grid named '{}' (the voxel set has: {})", op, name, names.empty() ? "none" : names));
}

/// The grid to write: the input itself, or a copy named `out`.
openvdb::GridBase::Ptr target(OpContext& ctx, const std::string& op)
{
    auto grid = requireGrid(ctx.set, op, ctx.args.text("grid"));
    if (!ctx.args.has("out") || ctx.args.text("out") == grid->getName()) return grid;
    auto copy = grid->deepCopyGrid();
    copy->setName(ctx.args.text("out"));
    ctx.set.put(copy);
    return copy;
}

/// Grid 'with' (B): from with_file when given, else from the set.
openvdb::GridBase::Ptr withGrid(OpContext& ctx, const std::string& op)
{
    if (ctx.args.has("with_file")) {
        const VoxelSet other = readVoxelSet(ctx.args.text("with_file"));
        return requireGrid(other, op, ctx.args.text("with"));
    }
    return requireGrid(ctx.set, op, ctx.args.text("with"));
}

const openvdb::BoolGrid* optionalSelection(OpContext& ctx, const std::string& op, const char* param, openvdb::BoolGrid::Ptr& keep)
{
    if (!ctx.args.has(param)) return nullptr;
    auto g = requireGrid(ctx.set, op, ctx.args.text(param));
    keep = openvdb::gridPtrCast<openvdb::BoolGrid>(g);
    if (!keep)
        throw UsageError(fmt::format(
            "{}: '{}' grid '{}' holds {} values; a selection is a bool grid (vxf op select)", op, param, g->getName(), g->valueType()));
    return keep.get();
}

std::string count(const openvdb::GridBase& g) { return fmt::format("{} active voxels", g.activeVoxelCount()); }

} // namespace vxf::ops::detail
