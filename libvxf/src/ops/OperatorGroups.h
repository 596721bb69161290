// vxf — the artist operators' declarations, in groups (ops/Registry.cc lists them in order), and
// what their run functions share: the common parameters and the grids they look up.
#pragma once

#include <vxf/ops/Registry.h>

#include <openvdb/Grid.h>
#include <openvdb/openvdb.h>

#include <string>
#include <vector>

namespace vxf::ops {

/// Arithmetic with a number, blend, blur, blur_special, normalize and denormalize.
std::vector<Operator> valueOperators();
/// gradient.
std::vector<Operator> colourOperators();
/// remove, include, select and edit.
std::vector<Operator> selectionOperators();
/// diff, apply_diff, split, merge, rename and copy.
std::vector<Operator> gridOperators();

namespace detail {

Param gridParam(const char* summary = "the grid to work on");
Param outParam();
Param withParam(const char* summary);
Param withFileParam();
/// The grid named @a name; vxf::UsageError naming @a op and listing the set's grids otherwise.
openvdb::GridBase::Ptr requireGrid(const VoxelSet& set, const std::string& op, const std::string& name);
/// The grid to write: the input itself, or a copy named `out`.
openvdb::GridBase::Ptr target(OpContext& ctx, const std::string& op);
/// Grid 'with' (B): from with_file when given, else from the set.
openvdb::GridBase::Ptr withGrid(OpContext& ctx, const std::string& op);
/// The bool grid named by parameter @a param, kept alive in @a keep; null when not given.
const openvdb::BoolGrid* optionalSelection(OpContext& ctx, const std::string& op, const char* param, openvdb::BoolGrid::Ptr& keep);
/// "N active voxels".
std::string count(const openvdb::GridBase& g);

} // namespace detail
} // namespace vxf::ops
