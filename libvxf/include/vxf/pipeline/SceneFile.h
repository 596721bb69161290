// vxf — scene files (schemas/scene.schema.json): read into the scene's types (vxf/core/Scene.h).
#pragma once

#include <vxf/core/Scene.h>

#include <string>

namespace vxf {

/// Read a scene file: JSON syntax errors name the line and column, schema violations
/// name the field (as a JSON pointer, e.g. /lights/1/cone_angle) and what was expected,
/// and geometric nonsense (a zero direction, an up vector along the view) is refused.
/// Relative mesh and grid paths are resolved against the scene file's folder.
/// Throws vxf::InputError.
Scene loadScene(const std::string& path);

/// Parse scene JSON text; @a path names it in messages and anchors relative paths.
Scene parseScene(const std::string& text, const std::string& path);

/// The JSON Schema scenes are checked against (schemas/scene.schema.json, embedded).
const std::string& sceneSchemaText();

} // namespace vxf
