// vxf — scene files (schemas/scene.schema.json): read into the scene's types (vxf/core/Scene.h).
#pragma once

#include <vxf/core/Scene.h>

#include <optional>
#include <string>
#include <vector>

namespace vxf {

/// Read a scene file: JSON syntax errors name the line and column, schema violations
/// name the field (as a JSON pointer, e.g. /lights/1/cone_angle) and what was expected,
/// and geometric nonsense (a zero direction, an up vector along the view) is refused.
/// Relative mesh and grid paths are resolved against the scene file's folder.
/// An animated scene (keyframed values, frame tokens in its paths) is read at @a frame: the
/// keyframes interpolated there, the paths' tokens expanded, the result checked again (errors
/// then say "at frame N"). Without a frame an animated scene is refused, naming what is
/// animated; a still scene read at a frame is the same at every frame.
/// A @a quality given overrides the scene's own `quality` (vxf/core/Quality.h): the setting
/// chosen for its error is read into the settings under the scene's own blocks, and said in
/// Scene::settings.quality.
/// Throws vxf::InputError.
Scene loadScene(
    const std::string& path, std::optional<int> frame = std::nullopt, const std::optional<QualityRequest>& quality = std::nullopt);

/// Parse scene JSON text; @a path names it in messages and anchors relative paths.
Scene parseScene(const std::string& text, const std::string& path, std::optional<int> frame = std::nullopt,
    const std::optional<QualityRequest>& quality = std::nullopt);

/// The JSON Schema scenes are checked against (schemas/scene.schema.json, embedded).
const std::string& sceneSchemaText();

} // namespace vxf
