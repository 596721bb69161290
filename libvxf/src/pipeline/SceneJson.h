// vxf — a scene's vectors and matrices as JSON (the stage cache's keys, a bake's manifest).
#pragma once

#include <nlohmann/json.hpp>
#include <openvdb/Types.h>

namespace vxf::detail {

inline nlohmann::json vecJson(const openvdb::Vec3d& v) { return nlohmann::json::array({v[0], v[1], v[2]}); }

/// Row by row, 16 numbers (OpenVDB's row-vector convention: the translation is the last row).
inline nlohmann::json matrixJson(const openvdb::Mat4d& m)
{
    nlohmann::json out = nlohmann::json::array();
    for (int r = 0; r < 4; ++r)
        for (int c = 0; c < 4; ++c) out.push_back(m(r, c));
    return out;
}

} // namespace vxf::detail
