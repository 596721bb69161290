#include <vxf/core/GridRoles.h>

#include <cctype>

namespace vxf {

const std::vector<GridRole>& gridRoles()
{
    using openvdb::GRID_FOG_VOLUME;
    using openvdb::GRID_LEVEL_SET;
    using openvdb::GRID_UNKNOWN;
    static const std::vector<GridRole> roles = {
        {"surface", "float", GRID_LEVEL_SET, "world units", "signed distance to the mesh, negative inside (narrow band)"},
        {"density", "float", GRID_FOG_VOLUME, "fraction", "medium density in [0,1]: scales sigma_a and sigma_s; 1 inside"},
        {"sigma_a", "vec3s", GRID_UNKNOWN, "1/world unit", "per-voxel absorption coefficient (RGB), replaces the material's"},
        {"sigma_s", "vec3s", GRID_UNKNOWN, "1/world unit", "per-voxel scattering coefficient (RGB), replaces the material's"},
        {"direct", "vec3s", GRID_UNKNOWN, "fluence", "fluence from the lights, attenuated by the medium (phi_0)"},
        {"scatter_source", "vec3s", GRID_UNKNOWN, "radiance/world unit",
            "in-scattered radiance per unit length, J_0 = sigma_s phi_0 / 4pi"},
        {"scatter_source_anisotropy", "vec3s", GRID_UNKNOWN, "direction",
            "with a forward phase: J_0's mean direction of travel a, J_0(w) = J_0 R(a, w), R the rest of the phase (Phase.h)"},
        {"scatter_pass_K", "vec3s", GRID_UNKNOWN, "fluence", "fluence added by scattering pass K (phi_K), kept on request"},
        {"scatter", "vec3s", GRID_UNKNOWN, "fluence", "sum of all scattering passes"},
        {"scatter_anisotropy", "vec3s", GRID_UNKNOWN, "direction",
            "with a forward phase: the scattered light's mean direction of travel F/phi"},
        {"illumination", "vec3s", GRID_UNKNOWN, "fluence", "direct + scatter"},
        {"mask", "bool", GRID_UNKNOWN, "selection", "voxel selection for the operators"},
        {"color", "vec3s", GRID_UNKNOWN, "linear RGB", "RGB copy for Blender/Cycles; the text VXF default column"},
        {"Cd", "vec3s", GRID_UNKNOWN, "linear RGB", "RGB copy named for Houdini"},
    };
    return roles;
}

const GridRole* findGridRole(const std::string& gridName)
{
    static const std::string passPrefix = "scatter_pass_";
    for (const GridRole& role : gridRoles()) {
        if (role.name == gridName) return &role;
    }
    if (gridName.size() > passPrefix.size() && gridName.compare(0, passPrefix.size(), passPrefix) == 0) {
        for (std::size_t i = passPrefix.size(); i < gridName.size(); ++i) {
            if (!std::isdigit(static_cast<unsigned char>(gridName[i]))) return nullptr;
        }
        for (const GridRole& role : gridRoles()) {
            if (role.name == "scatter_pass_K") return &role;
        }
    }
    return nullptr;
}

} // namespace vxf
