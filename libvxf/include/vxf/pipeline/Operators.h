// vxf — every operator: the artist operators (vxf/ops/Registry.h) and the pipeline's stages.
#pragma once

#include <vxf/ops/Registry.h>
#include <vxf/core/RenderedImage.h>
#include <vxf/core/Scene.h>
#include <vxf/light/DirectLight.h>
#include <vxf/render/Render.h>
#include <vxf/scatter/Scatter.h>
#include <vxf/voxelize/Voxelize.h>

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

/// The stage operators' checked arguments (findOperator("scatter") and so on) as the stage's
/// options. A graph's stage nodes and the stage commands (vxf voxelize, light, scatter, render,
/// whose options are those operators' parameters) both call these, so a stage's parameters,
/// defaults (vxf/core/StageDefaults.h) and help are declared once, in its operator.
VoxelizeOptions voxelizeOptions(const ops::Args& args);
/// The scene of the light and render stages' arguments: `scene` read at `frame` when given.
Scene stageScene(const ops::Args& args);
/// The march step is the scene's (scatter.step) unless `step` is given.
DirectLightOptions lightOptions(const ops::Args& args, const SceneSettings& settings);
/// The kernel is defaultScatterKernel(material.phaseG) unless `kernel` is given.
ScatterOptions scatterOptions(const ops::Args& args, const Material& material);
/// The scene's render settings, with the given overrides.
RenderOptions renderOptions(const ops::Args& args, const SceneSettings& settings);

/// Render @a set with @a scene's camera: camera rays hit the scene's meshes, or the set's
/// `surface` level set when @a levelSet (the scene's occluders still shadow).
RenderedImage renderScene(const VoxelSet& set, const Medium& medium, const Scene& scene, const RenderOptions& options, bool levelSet,
    Interrupter* interrupter = nullptr);

/// docs/cli.md's operator table (markdown), generated from operators().
std::string operatorTableMarkdown();

/// schemas/pipeline.schema.json, generated from operators(): a graph of named nodes, each an
/// operator with its checked parameters (or a file), and the outputs wanted.
nlohmann::json pipelineSchema();

} // namespace vxf
