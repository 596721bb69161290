#include <vxf/core/Frames.h>

#include <vxf/core/Error.h>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <regex>
#include <set>

namespace vxf {

namespace {

constexpr long kFirstFrame = -999999, kLastFrame = 9999999;
/// A shot's length at most (a range past it is a typo: `1-2400000` for `1-240`).
constexpr std::size_t kMaxFrames = 1000000;

[[noreturn]] void refuse(const std::string& part, const std::string& why)
{
    throw UsageError(fmt::format("--frames: '{}': {} (expected N, A-B, A-B:STEP or a comma-separated list of those)", part, why));
}

/// An integer frame (optionally negative) spelt wholly by @a text.
long frameNumber(const std::string& text, const std::string& part)
{
    if (text.empty()) refuse(part, "a frame number is missing");
    std::size_t digits = text[0] == '-' ? 1 : 0;
    if (digits == text.size()) refuse(part, "a frame number is missing");
    for (std::size_t i = digits; i < text.size(); ++i) {
        if (!std::isdigit(static_cast<unsigned char>(text[i]))) refuse(part, fmt::format("'{}' is not a whole frame number", text));
    }
    if (text.size() > 9) refuse(part, fmt::format("frame {} is out of range [{}, {}]", text, kFirstFrame, kLastFrame));
    const long frame = std::strtol(text.c_str(), nullptr, 10);
    if (frame < kFirstFrame || frame > kLastFrame)
        refuse(part, fmt::format("frame {} is out of range [{}, {}]", frame, kFirstFrame, kLastFrame));
    return frame;
}

} // namespace

std::vector<int> parseFrameRange(const std::string& spec)
{
    std::vector<int> frames;
    std::set<int> seen;
    std::size_t begin = 0;
    if (spec.empty()) refuse(spec, "no frames given");
    while (begin <= spec.size()) {
        const std::size_t comma = std::min(spec.find(',', begin), spec.size());
        const std::string part = spec.substr(begin, comma - begin);
        begin = comma + 1;
        if (part.empty()) refuse(spec, "an empty item in the list");
        // A-B[:STEP]: the dash that separates is the first one after the first character (A may be negative).
        const std::size_t colon = part.find(':');
        const std::string range = part.substr(0, colon);
        const std::size_t dash = range.find('-', 1);
        long first = 0, last = 0, step = 1;
        if (dash == std::string::npos) {
            if (colon != std::string::npos) refuse(part, "a step needs a range (A-B:STEP)");
            first = last = frameNumber(range, part);
        } else {
            first = frameNumber(range.substr(0, dash), part);
            last = frameNumber(range.substr(dash + 1), part);
            if (first > last) refuse(part, fmt::format("the range runs backwards ({} > {})", first, last));
            if (colon != std::string::npos) {
                step = frameNumber(part.substr(colon + 1), part);
                if (step < 1) refuse(part, fmt::format("the step must be at least 1, not {}", step));
            }
        }
        if (std::size_t((last - first) / step + 1) + frames.size() > kMaxFrames) {
            refuse(part, fmt::format("more than {} frames", kMaxFrames));
        }
        for (long f = first; f <= last; f += step) {
            if (seen.insert(int(f)).second) frames.push_back(int(f));
        }
    }
    return frames;
}

std::string paddedFrame(int frame, int digits)
{
    return frame < 0 ? fmt::format("-{:0{}d}", -frame, std::max(digits - 1, 1)) : fmt::format("{:0{}d}", frame, digits);
}

namespace {

/// The length of the token at @a at (a '$' or a '#') and the digits it pads to (0: as it is);
/// 0 length when @a at starts none. Throws for a Houdini variable vxf cannot expand.
std::size_t tokenAt(const std::string& path, std::size_t at, int& digits)
{
    digits = 0;
    if (path[at] == '#') {
        std::size_t end = at;
        while (end < path.size() && path[end] == '#') ++end;
        digits = int(end - at);
        return end - at;
    }
    if (path[at] != '$' || at + 1 >= path.size()) return 0;
    const bool braced = path[at + 1] == '{';
    std::size_t i = at + (braced ? 2 : 1);
    std::size_t nameEnd = i;
    while (nameEnd < path.size() && (std::isalnum(static_cast<unsigned char>(path[nameEnd])) || path[nameEnd] == '_')) ++nameEnd;
    const std::string name = path.substr(i, nameEnd - i);
    if (name.empty()) return 0;
    const bool frameToken = name == "F" || (name.size() == 2 && name[0] == 'F' && name[1] >= '1' && name[1] <= '9');
    if (!frameToken) {
        throw UsageError(fmt::format("{}: ${}{}{} is a variable vxf cannot expand (frame tokens: $F, $F4, ${{F4}}, ####)", path,
            braced ? "{" : "", name, braced ? "}" : ""));
    }
    if (braced && (nameEnd >= path.size() || path[nameEnd] != '}')) throw UsageError(fmt::format("{}: ${{{} lacks its '}}'", path, name));
    digits = name.size() == 2 ? name[1] - '0' : 0;
    return nameEnd - at + (braced ? 1 : 0);
}

} // namespace

std::string expandFrameTokens(const std::string& path, int frame)
{
    std::string out;
    out.reserve(path.size() + 8);
    for (std::size_t i = 0; i < path.size();) {
        int digits = 0;
        const std::size_t length = tokenAt(path, i, digits);
        if (length == 0) {
            out += path[i++];
            continue;
        }
        out += digits > 0 ? paddedFrame(frame, digits) : std::to_string(frame);
        i += length;
    }
    return out;
}

bool hasFrameTokens(const std::string& path)
{
    // (without expanding: a still path may hold a '$' of its own, `cost$.vdb` or `$HOME`, taken as it is)
    static const std::regex token(R"(#|\$\{F[1-9]?\}|\$F[1-9]?(?![A-Za-z0-9_]))");
    return std::regex_search(path, token);
}

} // namespace vxf
