#include "SceneAnimation.h"

#include <vxf/core/Error.h>
#include <vxf/core/Frames.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>

namespace vxf::detail {

namespace {

using nlohmann::json;

bool isCurve(const json& value) { return value.is_object() && value.contains("keyframes"); }

bool isFramePath(const std::string& key, const json& value)
{
    return value.is_string() && (key == "mesh" || key == "volume" || key == "file");
}

/// A JSON pointer's token (RFC 6901: '~' and '/' escaped).
std::string pointerToken(const std::string& key)
{
    std::string out;
    for (char c : key) out += c == '~' ? std::string("~0") : c == '/' ? std::string("~1") : std::string(1, c);
    return out;
}

template <typename Visit>
void walk(const json& value, const std::string& pointer, const Visit& visit)
{
    if (value.is_object()) {
        for (auto it = value.begin(); it != value.end(); ++it) {
            const std::string at = pointer + "/" + pointerToken(it.key());
            if (!visit(it.key(), it.value(), at)) walk(it.value(), at, visit);
        }
    } else if (value.is_array()) {
        for (std::size_t i = 0; i < value.size(); ++i) walk(value[i], pointer + "/" + std::to_string(i), visit);
    }
}

/// One key of a curve, its value as up to three components.
struct Key
{
    double frame = 0.0;
    std::array<double, 3> value{};
    std::string interpolation;
};

/// Hermite tangents of Blender's and Houdini's automatic clamped handles: zero at the first and
/// last key and at a peak or a trough, else the slope through the two neighbours limited so that
/// the cubic does not overshoot its keys (Fritsch and Carlson 1980: monotone between keys).
std::vector<double> clampedTangents(const std::vector<Key>& keys, int c)
{
    const std::size_t n = keys.size();
    std::vector<double> tangent(n, 0.0);
    for (std::size_t i = 1; i + 1 < n; ++i) {
        const double before = (keys[i].value[c] - keys[i - 1].value[c]) / (keys[i].frame - keys[i - 1].frame);
        const double after = (keys[i + 1].value[c] - keys[i].value[c]) / (keys[i + 1].frame - keys[i].frame);
        if (before * after <= 0.0) continue; // a peak, a trough or a flat: the handle is level
        const double slope = (keys[i + 1].value[c] - keys[i - 1].value[c]) / (keys[i + 1].frame - keys[i - 1].frame);
        tangent[i] = std::copysign(std::min({std::abs(slope), 3.0 * std::abs(before), 3.0 * std::abs(after)}), slope);
    }
    return tangent;
}

} // namespace

json evaluateKeyframes(const json& curve, double frame, const std::string& where)
{
    const std::string defaultInterpolation = curve.value("interpolation", std::string("linear"));
    std::vector<Key> keys;
    const bool triple = curve["keyframes"][0]["value"].is_array();
    for (const json& k : curve["keyframes"]) {
        Key key;
        key.frame = k["frame"].get<double>();
        const json& v = k["value"];
        if (v.is_array() != triple) throw InputError(where, 0, 0, "a curve's values must be all numbers or all triples");
        for (int c = 0; c < (triple ? 3 : 1); ++c) key.value[std::size_t(c)] = triple ? v[std::size_t(c)].get<double>() : v.get<double>();
        key.interpolation = k.value("interpolation", defaultInterpolation);
        if (!keys.empty() && !(key.frame > keys.back().frame)) {
            throw InputError(
                where, 0, 0, fmt::format("the keys must run forward in frames (frame {} follows frame {})", key.frame, keys.back().frame));
        }
        keys.push_back(std::move(key));
    }
    std::array<double, 3> out{};
    const int components = triple ? 3 : 1;
    if (frame <= keys.front().frame || keys.size() == 1) {
        out = keys.front().value;
    } else if (frame >= keys.back().frame) {
        out = keys.back().value;
    } else {
        std::size_t i = 0;
        while (keys[i + 1].frame <= frame) ++i;
        const Key &a = keys[i], &b = keys[i + 1];
        const double span = b.frame - a.frame, t = (frame - a.frame) / span;
        for (int c = 0; c < components; ++c) {
            const double va = a.value[std::size_t(c)], vb = b.value[std::size_t(c)];
            double v = va + (vb - va) * t; // linear
            if (a.interpolation == "constant") {
                v = va;
            } else if (a.interpolation == "ease") {
                v = va + (vb - va) * t * t * (3.0 - 2.0 * t);
            } else if (a.interpolation == "bezier") {
                const std::vector<double> m = clampedTangents(keys, c);
                const double t2 = t * t, t3 = t2 * t;
                v = (2 * t3 - 3 * t2 + 1) * va + (t3 - 2 * t2 + t) * span * m[i] + (-2 * t3 + 3 * t2) * vb + (t3 - t2) * span * m[i + 1];
            }
            out[std::size_t(c)] = v;
        }
    }
    if (!triple) return out[0];
    return json::array({out[0], out[1], out[2]});
}

std::vector<std::string> animatedValues(const json& document)
{
    std::vector<std::string> found;
    walk(document, "", [&](const std::string& key, const json& value, const std::string& at) {
        if (isCurve(value) || (isFramePath(key, value) && hasFrameTokens(value.get<std::string>()))) {
            found.push_back(at);
            return true;
        }
        return false;
    });
    return found;
}

json sceneAtFrame(const json& document, int frame, const std::string& path)
{
    json out = document;
    for (const std::string& at : animatedValues(document)) {
        const json::json_pointer pointer(at);
        const json& value = document.at(pointer);
        out[pointer] =
            isCurve(value) ? evaluateKeyframes(value, frame, path + ": " + at) : json(expandFrameTokens(value.get<std::string>(), frame));
    }
    return out;
}

} // namespace vxf::detail
