// vxf — the node graph: a DAG of operators over voxel sets, run with caching (`vxf graph`).
#pragma once

#include <vxf/core/Interrupter.h>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace vxf {

struct GraphNodeRecord
{
    std::string node;
    std::string action; ///< "ran" or "reused"
    std::string why; ///< one phrase for a person
    std::string report; ///< the operator's own report ("" when reused)
    double seconds = 0.0;
};

struct GraphReport
{
    std::vector<GraphNodeRecord> nodes; ///< in evaluation order
    std::vector<std::pair<std::string, std::string>> written; ///< (node, file)
};

/// The schema pipelines are checked against (generated from the operator registry).
const nlohmann::json& pipelineSchemaJson();

/// Run the pipeline at @a path (schemas/pipeline.schema.json): named nodes, each a source
/// `.vdb` file or an operator applied to the voxel set of its `input` node, and `outputs`
/// (node → file to write). Only the nodes the outputs need are evaluated. Each node's
/// voxel set is cached in @a cacheDir as NODE-HASH.vdb, HASH covering its operator, checked
/// parameters, the files its parameters name (their bytes) and its input's hash (a source:
/// its file's bytes), so a second run does no work and a changed parameter recomputes only
/// what lies downstream. Relative paths are resolved against the pipeline file's folder.
/// Errors: JSON syntax (line:column), schema (field), unknown input nodes, cycles and bad
/// parameters are vxf::InputError / vxf::UsageError naming the file and the node.
GraphReport runGraph(const std::string& path, const std::string& cacheDir, Interrupter* interrupter = nullptr);

/// Check the pipeline at @a path as runGraph does before any work (syntax, schema, operators,
/// inputs, parameters, outputs), reading and writing nothing else; the same errors.
void checkGraph(const std::string& path);

/// Append one operator step to the pipeline at @a graphPath (created when missing): a node
/// running @a op with @a params on @a input — the node that last wrote @a input, or a new
/// source node for it — and @a output as its output file. So a sequence of one-off
/// `vxf op … --record P.json` commands becomes a reusable graph. Paths are stored relative
/// to the pipeline's folder when they lie under it. Written atomically.
void recordStep(
    const std::string& graphPath, const std::string& op, const nlohmann::json& params, const std::string& input, const std::string& output);

} // namespace vxf
