// vxf — the `quality` setting applied to a scene's settings (vxf/core/Quality.h says what it is).
#pragma once

#include <vxf/core/Scene.h>

#include <nlohmann/json.hpp>

#include <string>

namespace vxf::detail {

/// What a scene's medium is like, as the accuracy bench's scenes are told apart.
struct QualityMedium
{
    bool volume = false; ///< a volume object (smoke, fire) rather than a mesh's interior
    double albedo = 0.0; ///< σs/σt, the mean of the channels
    double phaseG = 0.0; ///< Henyey-Greenstein g
    /// A mesh medium's size in mean free paths: its media's joint bounds' longest side × σt
    /// (the mean of the channels); 0 when not known (a volume object).
    double opticalSize = 0.0;
};

/// The bench's table (QualityTable.json, compiled in).
const nlohmann::json& qualityTable();

/// Chooses, for @a request and a scene whose medium is @a medium, the fastest setting of the
/// closest bench scene that reached the error, and writes its knobs into @a settings, except
/// the knobs @a document (the scene file) sets itself: the caller applies those after. The
/// phase's own defaults (sweep kernel, single scattering marched to the lights) stay when the
/// scene's phase is anisotropic and the bench scene's is not.
QualityChoice applyQuality(
    const QualityRequest& request, const QualityMedium& medium, const nlohmann::json& document, SceneSettings& settings);

} // namespace vxf::detail
