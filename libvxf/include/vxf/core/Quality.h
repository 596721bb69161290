// vxf — accuracy as a setting. A scene's `"quality": {"error": 0.05}` (or "draft", "final",
// "reference"), or `vxf run --error` / `--quality`, asks for an error; the scene is read with the
// fastest setting bench/accuracy measured to reach it on the closest of its scenes (the table
// the bench writes into libvxf/src/pipeline/QualityTable.json), under the knobs the scene sets
// itself. What was chosen, and why, is a QualityChoice the run prints.
#pragma once

#include <string>
#include <vector>

namespace vxf {

/// An error asked for: a relative RMSE against a path-traced reference (bench/accuracy's
/// measure), given as a number or by a level's name.
struct QualityRequest
{
    double error = 0.0; ///< the relative RMSE; taken from the level when one is named
    std::string level; ///< draft, final or reference; "" when the error is given
};

/// The relative RMSE a level names: draft 0.10, final 0.05, reference 0.02. Throws
/// vxf::UsageError naming the levels for any other name.
double qualityLevelError(const std::string& level);

/// The request a level makes (its error, and its name for the run to say). Throws as
/// qualityLevelError.
inline QualityRequest qualityRequestForLevel(const std::string& level) { return QualityRequest{qualityLevelError(level), level}; }

/// The names of the levels, in the order of their errors (draft first).
const std::vector<std::string>& qualityLevels();

/// What a quality request chose.
struct QualityChoice
{
    QualityRequest asked;
    std::string benchScene; ///< the accuracy bench's scene it is closest to (thick, translucent, smoke, ...)
    std::string why; ///< what makes that scene the closest, in words
    std::string setting; ///< the bench's words for the setting taken (its knobs off the bench's base)
    double error = 0.0, seconds = 0.0; ///< what the setting reached on the bench, and in what wall time
    bool reached = true; ///< false: no measured setting reaches the error asked; the most accurate was taken
    std::vector<std::string> kept; ///< the knobs the scene sets itself, which win (as /block/key)
    int environmentSamples = 0; ///< samples of the environment lights that set none (0: their default)

    /// A paragraph for the run's output: asked, chosen, why, and what the scene kept.
    std::string summary() const;
};

} // namespace vxf
