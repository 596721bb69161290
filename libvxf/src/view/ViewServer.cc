#include <vxf/view/ViewServer.h>

#include <httplib.h>

#include <fmt/format.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>

#include <unistd.h>

namespace vxf::view {

namespace detail {
// The page, its script and three.js (ViewAssets.cc, generated from libvxf/src/view/web and third_party/three).
extern const char* const kIndexHtml;
extern const char* const kViewJs;
extern const char* const kThreeJs;
extern const char* const kOrbitControlsJs;
} // namespace detail

namespace {

/// Requests larger than this are refused (an edit is a few hundred bytes of JSON).
constexpr std::size_t kMaxRequestBytes = 1 << 20;
/// The most points one request may ask for.
constexpr std::size_t kMaxPointBudget = 4'000'000;

// Content types that cpp-httplib does not compress on the fly: with Brotli (Debian builds it so)
// a 670 KB script took 1.9 s to send over the loopback, where it needs 2 ms as it is.
constexpr const char* kJson = "application/json; charset=utf-8";
constexpr const char* kJavaScript = "application/x-javascript; charset=utf-8";

void sendError(httplib::Response& res, int status, const std::string& message)
{
    res.status = status;
    res.set_content(nlohmann::json{{"error", message}}.dump(), kJson);
}

void sendJson(httplib::Response& res, const nlohmann::json& body) { res.set_content(body.dump(), kJson); }

template <typename T>
void append(std::string& out, const T* data, std::size_t count)
{
    out.append(reinterpret_cast<const char*>(data), count * sizeof(T));
}

std::string param(const httplib::Request& req, const char* name)
{
    if (!req.has_param(name)) throw UsageError(fmt::format("missing query parameter '{}'", name));
    return req.get_param_value(name);
}

long long integerParam(const httplib::Request& req, const char* name, long long fallback)
{
    if (!req.has_param(name)) return fallback;
    const std::string text = req.get_param_value(name);
    std::size_t used = 0;
    long long value = 0;
    try {
        value = std::stoll(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    if (used == 0 || used != text.size()) throw UsageError(fmt::format("query parameter '{}': '{}' is not a whole number", name, text));
    return value;
}

nlohmann::json bodyJson(const httplib::Request& req)
{
    nlohmann::json body = nlohmann::json::parse(req.body, nullptr, /*allow_exceptions=*/false);
    if (body.is_discarded() || !body.is_object()) throw UsageError("the request body is not a JSON object");
    return body;
}

std::string stringField(const nlohmann::json& body, const char* name, const std::string& fallback = {}, bool required = true)
{
    if (!body.contains(name)) {
        if (required) throw UsageError(fmt::format("the request lacks '{}'", name));
        return fallback;
    }
    if (!body[name].is_string()) throw UsageError(fmt::format("'{}' must be a string", name));
    return body[name].get<std::string>();
}

} // namespace

struct ViewServer::Impl
{
    ViewSession& session;
    ViewServerOptions options;
    bool ownFolder = false;
    httplib::Server server;
    std::mutex renderMutex;
    std::string lastPng;
    Impl(ViewSession& s, ViewServerOptions o)
        : session(s)
        , options(std::move(o))
    {
        if (options.renderFolder.empty()) {
            options.renderFolder = (std::filesystem::temp_directory_path() / fmt::format("vxf-view-{}-{}", ::getpid(),
                reinterpret_cast<std::uintptr_t>(this))).string();
            ownFolder = true;
        }
    }
    ~Impl()
    {
        std::error_code ignored;
        if (ownFolder) std::filesystem::remove_all(options.renderFolder, ignored);
    }
};

ViewServer::ViewServer(ViewSession& session, ViewServerOptions options)
    : mImpl(std::make_unique<Impl>(session, std::move(options)))
{
    httplib::Server& server = mImpl->server;
    ViewSession& s = session;
    Impl& impl = *mImpl;
    server.set_payload_max_length(kMaxRequestBytes);
    // vxf's errors from bad input are the client's (400); anything else is the server's (500).
    server.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
        try {
            std::rethrow_exception(ep);
        } catch (const Error& e) {
            sendError(res, 400, e.what());
        } catch (const std::exception& e) {
            sendError(res, 500, e.what());
        } catch (...) {
            sendError(res, 500, "unknown error");
        }
    });
    const auto asset = [&server](const char* path, const char* const& body, const char* type) {
        server.Get(path, [&body, type](const httplib::Request&, httplib::Response& res) {
            res.set_content(body, std::strlen(body), type);
        });
    };
    asset("/", detail::kIndexHtml, "text/html; charset=utf-8");
    asset("/view.js", detail::kViewJs, kJavaScript);
    asset("/three.module.min.js", detail::kThreeJs, kJavaScript);
    asset("/OrbitControls.js", detail::kOrbitControlsJs, kJavaScript);

    server.Get("/favicon.ico", [](const httplib::Request&, httplib::Response& res) { res.status = 204; });
    server.Get("/api/info", [&s, &impl](const httplib::Request&, httplib::Response& res) {
        nlohmann::json info = s.describe();
        info["scene"] = impl.options.scene.empty() ? nlohmann::json(nullptr) : nlohmann::json(impl.options.scene);
        sendJson(res, info);
    });
    server.Post("/api/render", [&s, &impl](const httplib::Request& req, httplib::Response& res) {
        if (impl.options.scene.empty()) throw UsageError("no scene to render with: start vxf view with --scene S.json");
        const nlohmann::json body = bodyJson(req);
        const auto dimension = [&](const char* key, int fallback) {
            if (!body.contains(key)) return fallback;
            if (!body[key].is_number_integer() || body[key].get<long long>() < 1 || body[key].get<long long>() > 8192) {
                throw UsageError(fmt::format("'{}' must be a whole number of pixels in [1, 8192]", key));
            }
            return body[key].get<int>();
        };
        const int width = dimension("width", 480), height = dimension("height", 360);
        std::lock_guard<std::mutex> lock(impl.renderMutex);
        const ViewSession::Rendered r = s.render(impl.options.scene, width, height, impl.options.renderFolder);
        impl.lastPng = r.png;
        sendJson(res, {{"ran", r.ran}, {"seconds", r.seconds}});
    });
    server.Get("/api/image", [&impl](const httplib::Request&, httplib::Response& res) {
        std::lock_guard<std::mutex> lock(impl.renderMutex);
        std::ifstream file(impl.lastPng, std::ios::binary);
        if (impl.lastPng.empty() || !file) {
            sendError(res, 404, "nothing rendered yet (POST /api/render)");
            return;
        }
        res.set_content(std::string(std::istreambuf_iterator<char>(file), {}), "image/png");
    });
    server.Get("/api/points", [&s](const httplib::Request& req, httplib::Response& res) {
        const long long budget = integerParam(req, "budget", 200000);
        if (budget < 1 || std::size_t(budget) > kMaxPointBudget) {
            throw UsageError(fmt::format("query parameter 'budget': {} is not in [1, {}]", budget, kMaxPointBudget));
        }
        const PointCloud cloud = s.points(param(req, "grid"), std::size_t(budget));
        const std::size_t count = cloud.positions.size() / 3;
        std::string body;
        body.reserve(count * std::size_t(3 + cloud.channels) * sizeof(float));
        for (std::size_t i = 0; i < count; ++i) {
            append(body, &cloud.positions[3 * i], 3);
            append(body, &cloud.values[std::size_t(cloud.channels) * i], std::size_t(cloud.channels));
        }
        res.set_header("X-Vxf-Count", std::to_string(count));
        res.set_header("X-Vxf-Channels", std::to_string(cloud.channels));
        res.set_header("X-Vxf-Cell-Voxels", std::to_string(cloud.cellVoxels));
        res.set_header("X-Vxf-Cell-Size", fmt::format("{}", cloud.cellSize));
        res.set_header("X-Vxf-Min", fmt::format("{}", cloud.minValue));
        res.set_header("X-Vxf-Max", fmt::format("{}", cloud.maxValue));
        res.set_header("X-Vxf-Active", std::to_string(cloud.activeVoxels));
        res.set_content(body, "application/octet-stream");
    });
    server.Get("/api/slice", [&s](const httplib::Request& req, httplib::Response& res) {
        const long long axis = integerParam(req, "axis", 2), index = integerParam(req, "index", 0);
        if (axis < 0 || axis > 2) throw UsageError(fmt::format("query parameter 'axis': {} is not 0, 1 or 2", axis));
        const Slice slice = s.slice(param(req, "grid"), int(axis), int(std::clamp<long long>(index, INT32_MIN / 2, INT32_MAX / 2)));
        nlohmann::json values = nlohmann::json::array();
        for (float v : slice.values) values.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr));
        sendJson(res, {{"axis", slice.axis}, {"index", slice.index}, {"origin", {slice.origin.x(), slice.origin.y(), slice.origin.z()}},
            {"width", slice.width}, {"height", slice.height}, {"channels", slice.channels}, {"values", values}});
    });
    server.Get("/api/mesh", [&s](const httplib::Request& req, httplib::Response& res) {
        const long long budget = integerParam(req, "triangles", 30000);
        if (budget < 1 || budget > 10'000'000) throw UsageError(fmt::format("query parameter 'triangles': {} is not in [1, 1e7]", budget));
        const SurfaceMesh mesh = s.surfaceMesh(std::size_t(budget));
        const std::uint32_t counts[2] = {std::uint32_t(mesh.positions.size() / 3), std::uint32_t(mesh.triangles.size() / 3)};
        std::string body;
        append(body, counts, 2);
        append(body, mesh.positions.data(), mesh.positions.size());
        append(body, mesh.triangles.data(), mesh.triangles.size());
        res.set_content(body, "application/octet-stream");
    });
    server.Get("/api/pipeline", [&s](const httplib::Request& req, httplib::Response& res) {
        sendJson(res, s.pipeline(req.has_param("output") ? req.get_param_value("output") : "edited.vdb"));
    });
    server.Post("/api/apply", [&s](const httplib::Request& req, httplib::Response& res) {
        const nlohmann::json body = bodyJson(req);
        const nlohmann::json params = body.contains("params") ? body["params"] : nlohmann::json::object();
        const std::string report = s.apply(stringField(body, "op"), params);
        sendJson(res, {{"report", report}, {"steps", s.steps()}});
    });
    server.Post("/api/undo", [&s](const httplib::Request&, httplib::Response& res) {
        const bool undone = s.undo();
        sendJson(res, {{"undone", undone}, {"steps", s.steps()}});
    });
    server.Post("/api/export", [&s](const httplib::Request& req, httplib::Response& res) {
        const nlohmann::json body = bodyJson(req);
        const std::string mode = stringField(body, "mode", "whole", false);
        ExportMode m;
        if (mode == "whole") m = ExportMode::Whole;
        else if (mode == "diff") m = ExportMode::Diff;
        else if (mode == "smoothed") m = ExportMode::Smoothed;
        else throw UsageError(fmt::format("export mode '{}' is not whole, diff or smoothed", mode));
        int smooth = 2;
        if (body.contains("smooth")) {
            if (!body["smooth"].is_number_integer()) throw UsageError("'smooth' must be a whole number of voxels");
            smooth = body["smooth"].get<int>();
        }
        const std::string written = s.exportTo(stringField(body, "path"), m, stringField(body, "grid", "", m != ExportMode::Whole), smooth);
        sendJson(res, {{"written", written}});
    });
    server.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
        if (res.status == 404 && res.body.empty()) sendError(res, 404, fmt::format("no such page or request: {}", req.path));
    });
}

ViewServer::~ViewServer() = default;

int ViewServer::bind(const std::string& host, int port)
{
    if (port == 0) {
        const int bound = mImpl->server.bind_to_any_port(host);
        if (bound <= 0) throw Error(fmt::format("view: cannot listen on {} (any port)", host));
        return bound;
    }
    if (!mImpl->server.bind_to_port(host, port)) throw Error(fmt::format("view: cannot listen on {}:{} (in use? try --port 0)", host, port));
    return port;
}

void ViewServer::listen() { mImpl->server.listen_after_bind(); }

void ViewServer::stop() { mImpl->server.stop(); }

} // namespace vxf::view
