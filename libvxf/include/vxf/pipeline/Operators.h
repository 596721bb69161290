// vxf — every operator: the artist operators (vxf/ops/Registry.h) and the pipeline's stages.
#pragma once

#include <vxf/ops/Registry.h>

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace vxf {

/// Every operator, in the order help lists them: the artist operators, then the pipeline
/// stages a graph can run (voxelize, light, scatter, render), registered here so that ops/
/// needs nothing above it.
const std::vector<ops::Operator>& operators();

/// The operator named @a name; vxf::UsageError listing the names otherwise.
const ops::Operator& findOperator(const std::string& name);

/// docs/cli.md's operator table (markdown), generated from operators().
std::string operatorTableMarkdown();

/// schemas/pipeline.schema.json, generated from operators(): a graph of named nodes, each an
/// operator with its checked parameters (or a file), and the outputs wanted.
nlohmann::json pipelineSchema();

} // namespace vxf
