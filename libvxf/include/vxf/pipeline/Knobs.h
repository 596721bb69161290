// vxf — every setting of the stages, declared once.
//
// A knob is one entry of a scene's `voxelize`, `scatter` or `render` block: its name, type,
// range, default and help (an ops::Param), the stages whose result it changes, whether the
// accuracy bench's quality table may set it, and how it is read from and written into
// SceneSettings. Everything else is made from the table: the scene reader (readKnobs), the
// blocks of schemas/scene.schema.json (knobSchema), the cached stages' keys (stageSettingsKey),
// the quality table's knobs (Quality.cc), the stage operators' parameters and so the stage
// commands' options, docs/cli.md and the pipeline schema (pipeline/Operators.cc). Nothing else
// names a knob.
#pragma once

#include <vxf/core/Scene.h>
#include <vxf/ops/Registry.h>

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace vxf {

/// The stages whose result a setting can change: a cached stage's key holds every knob it reads.
enum class Stage { Voxelize, Light, Scatter, Render };

/// One setting of a scene's blocks.
struct Knob
{
    std::string block; ///< the scene's block it sits in: voxelize, scatter or render
    /// Its name (as in the scene, the stage operator, the CLI with '-' for '_', and Python), type,
    /// help, range and default. A null default: the scene's medium chooses (a phase's kernel), or
    /// the knob is off until given (voxel_size).
    ops::Param param;
    std::vector<Stage> readBy; ///< the stages whose result it changes
    bool quality = false; ///< the quality table's settings may set it, by this name (QualityTable.json)
    std::function<nlohmann::json(const SceneSettings&)> get; ///< its value in @a settings, as the scene writes it
    std::function<void(SceneSettings&, const nlohmann::json&)> set; ///< write a value checked by the schema

    /// "/block/name", as messages and the quality's kept knobs name it.
    std::string path() const { return "/" + block + "/" + param.name; }
    bool reads(Stage stage) const;
};

/// Every knob, in the order of the blocks (voxelize, scatter, render) and of their help.
const std::vector<Knob>& knobs();

/// The knob @a name of @a block; vxf::Error when there is none (a declaration missing: a bug).
const Knob& findKnob(const std::string& block, const std::string& name);

/// Write the knobs @a document's blocks give into @a settings (the document checked by the
/// scene schema, so each value has its type and range); knobs it leaves out keep their value.
void readKnobs(const nlohmann::json& document, SceneSettings& settings);

/// Whether @a document (a scene) gives @a knob itself.
bool givesKnob(const nlohmann::json& document, const Knob& knob);

/// The JSON Schema of a block's `properties` (each knob's type, range, choices and help).
nlohmann::json knobSchema(const std::string& block);

/// The scene schema: schemas/scene.schema.json with its voxelize, scatter and render blocks'
/// properties made from the knobs (the committed file is this, written by scripts/generate).
const nlohmann::json& sceneSchemaDocument();

/// The settings part of @a stage's cache key: each knob @a stage reads, by path, with its value.
nlohmann::json stageSettingsKey(const SceneSettings& settings, Stage stage);

/// @a knob as a parameter of a stage operator that reads a scene (light, render): optional, the
/// scene's value when not given, its help saying so.
ops::Param sceneOverride(const Knob& knob);

} // namespace vxf
