// vxf — an animated scene at one frame: keyframed values interpolated, frame tokens in paths
// expanded (schemas/scene.schema.json, definitions/keyframes).
#pragma once

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace vxf::detail {

/// Where @a document (a scene, already checked against the schema) is animated: the JSON
/// pointers of its keyframed values and of its paths holding frame tokens. Empty: a still scene.
std::vector<std::string> animatedValues(const nlohmann::json& document);

/// @a document at @a frame: every keyframed value replaced by its value there, every mesh,
/// volume and file path's frame tokens expanded (vxf/core/Frames.h). A curve's keys must run
/// forward in frames, and be all numbers or all triples: InputError of @a path otherwise,
/// naming the value's pointer.
nlohmann::json sceneAtFrame(const nlohmann::json& document, int frame, const std::string& path);

/// The value of the keyframe curve @a curve (a `{"keyframes": [...]}` object) at @a frame;
/// @a where names it in errors (path: pointer).
nlohmann::json evaluateKeyframes(const nlohmann::json& curve, double frame, const std::string& where);

} // namespace vxf::detail
