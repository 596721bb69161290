// vxf — the named grid roles of a voxel set (the table in schemas/voxelset.md).
#pragma once

#include <openvdb/Grid.h>

#include <string>
#include <vector>

namespace vxf {

/// One role a grid of a voxel set can play, keyed by the grid's name.
struct GridRole
{
    std::string name; ///< grid name; "scatter_pass_K" stands for scatter_pass_1, _2, …
    std::string valueType; ///< OpenVDB value type name: "float", "vec3s", "bool"
    openvdb::GridClass gridClass;
    std::string units; ///< written to the grid's "vxf:units" metadata
    std::string description; ///< one line, for `vxf info` and the spec
};

/// Every role DESIGN.md defines, in pipeline order.
const std::vector<GridRole>& gridRoles();

/// The role a grid named @a gridName plays, or nullptr for a grid vxf does not know
/// (such grids are carried through every stage untouched).
const GridRole* findGridRole(const std::string& gridName);

/// The grid names of the roles, written once (schemas/voxelset.md).
namespace grids {
inline constexpr const char* kSurface = "surface";
inline constexpr const char* kDensity = "density";
inline constexpr const char* kSigmaA = "sigma_a";
inline constexpr const char* kSigmaS = "sigma_s";
inline constexpr const char* kDirect = "direct";
inline constexpr const char* kScatterSource = "scatter_source";
/// The light stage's mean direction of the scattered light's travel (an anisotropic phase).
inline constexpr const char* kSourceAnisotropy = "scatter_source_anisotropy";
inline constexpr const char* kScatter = "scatter";
/// The scatter stage's mean direction of the multiply scattered light's travel.
inline constexpr const char* kScatterAnisotropy = "scatter_anisotropy";
inline constexpr const char* kIllumination = "illumination";
inline constexpr const char* kMask = "mask";
} // namespace grids

/// Metadata key for the units of a grid's values.
inline constexpr const char* kUnitsMetaKey = "vxf:units";

} // namespace vxf
