#include <vxf/view/ViewServer.h>

#include <httplib.h>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <random>

#include <unistd.h>

namespace vxf::view {

namespace detail {
// The page, its script and three.js (ViewAssets.cc, generated from libvxf/src/view/web and third_party/three).
extern const char* const kIndexHtml;
extern const char* const kViewJs;
extern const char* const kThreeJs;
extern const char* const kOrbitControlsJs;
extern const char* const kTransformControlsJs;
} // namespace detail

namespace {

/// Requests larger than this are refused (an edit is a few hundred bytes of JSON).
constexpr std::size_t kMaxRequestBytes = 1 << 20;
/// A connection that sends nothing for this long is closed (a half-sent request holds a worker
/// thread only this long); and the workers, enough that dozens of such requests leave the page
/// answered at once.
constexpr time_t kReadTimeoutSeconds = 2, kKeepAliveSeconds = 2;
constexpr std::size_t kWorkerThreads = 96;
/// The secret's length in bytes (printed as hex in the page's address).
constexpr std::size_t kTokenBytes = 16;
/// The most points one request may ask for.
constexpr std::size_t kMaxPointBudget = 4'000'000;
/// The largest brick /api/volume sends (cells): 256³, 256 MiB of a Vec3 grid's floats.
constexpr long long kMaxVolumeCells = 256LL * 256 * 256;

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

/// A fresh secret from the system's entropy source (std::random_device reads /dev/urandom).
std::string newToken()
{
    std::random_device entropy;
    std::string token;
    for (std::size_t i = 0; i < kTokenBytes; i += 4) token += fmt::format("{:08x}", std::uint32_t(entropy()));
    return token;
}

/// Equal strings, compared in a time that does not depend on where they first differ.
bool sameSecret(const std::string& a, const std::string& b)
{
    if (a.size() != b.size()) return false;
    unsigned char diff = 0;
    for (std::size_t i = 0; i < a.size(); ++i) diff |= static_cast<unsigned char>(a[i] ^ b[i]);
    return diff == 0;
}

/// The media type of a Content-Type value, lower case, without its parameters.
std::string mediaType(const std::string& contentType)
{
    std::string type = contentType.substr(0, contentType.find(';'));
    type.erase(std::remove_if(type.begin(), type.end(), [](unsigned char c) { return std::isspace(c); }), type.end());
    std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return char(std::tolower(c)); });
    return type;
}

} // namespace

/// A render's progress as the stages report it (OpenVDB's interrupter interface): the stage and
/// its percent, read by GET /api/progress while the render runs on its own request's thread.
class RenderProgress : public Interrupter
{
public:
    void begin()
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mRunning = true;
        mStep = "starting";
        mPercent = 0;
        mStart = std::chrono::steady_clock::now();
    }
    void finish()
    {
        std::lock_guard<std::mutex> lock(mMutex);
        mRunning = false;
    }
    void start(const char* name) override
    {
        std::lock_guard<std::mutex> lock(mMutex);
        if (name) mStep = name;
        mPercent = 0;
    }
    bool wasInterrupted(int percent) override
    {
        if (percent >= 0) {
            std::lock_guard<std::mutex> lock(mMutex);
            mPercent = std::max(mPercent, std::min(percent, 100));
        }
        return false;
    }
    nlohmann::json state() const
    {
        std::lock_guard<std::mutex> lock(mMutex);
        return {{"rendering", mRunning}, {"step", mStep}, {"percent", mPercent},
            {"seconds", mRunning ? std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count() : 0.0}};
    }

private:
    mutable std::mutex mMutex;
    bool mRunning = false;
    std::string mStep;
    int mPercent = 0;
    std::chrono::steady_clock::time_point mStart;
};

struct ViewServer::Impl
{
    ViewSession& session;
    ViewServerOptions options;
    bool ownFolder = false;
    httplib::Server server;
    std::mutex renderMutex; ///< one render at a time, and the last one's image
    RenderProgress progress;
    std::string lastPng;
    std::string host; ///< the bound address and port
    int port = 0;

    /// Whether a request's Host names this server: the bound address or a loopback name, with
    /// the bound port. A page of another name resolving to 127.0.0.1 (DNS rebinding) does not.
    /// Bound to every interface (0.0.0.0, ::), any name is taken: the secret guards it.
    bool hostAllowed(const std::string& value) const
    {
        if (host == "0.0.0.0" || host == "::") return true;
        const std::string suffix = fmt::format(":{}", port);
        for (const std::string& name : {host, std::string("127.0.0.1"), std::string("localhost"), std::string("[::1]")}) {
            const std::string bracketed = name.find(':') != std::string::npos && name.front() != '[' ? "[" + name + "]" : name;
            if (value == bracketed + suffix || (port == 80 && value == bracketed)) return true;
        }
        return false;
    }
    /// Whether an Origin header is this server's own page.
    bool originAllowed(const std::string& origin) const
    {
        const std::string scheme = "http://";
        return origin.compare(0, scheme.size(), scheme) == 0 && hostAllowed(origin.substr(scheme.size()));
    }
    Impl(ViewSession& s, ViewServerOptions o)
        : session(s)
        , options(std::move(o))
    {
        if (options.renderFolder.empty()) {
            options.renderFolder =
                (std::filesystem::temp_directory_path() / fmt::format("vxf-view-{}-{}", ::getpid(), reinterpret_cast<std::uintptr_t>(this)))
                    .string();
            ownFolder = true;
        }
    }

    /// Before any page or request: the Host, the session's secret, the Origin and the body's type;
    /// vxf's errors from bad input answered 400, anything else 500.
    void guardRequests()
    {
        Impl& impl = *this;
        // Before any page or request: a Host of this server's (DNS rebinding); for the API the
        // session's secret (another page on this machine cannot know it); for every request that
        // changes or writes, the page's own Origin and a JSON body (a cross-origin form or text/plain
        // POST, which a browser sends without asking, is refused before it is read).
        server.set_pre_routing_handler([&impl](const httplib::Request& req, httplib::Response& res) {
            const auto refuse = [&res](int status, const std::string& why) {
                sendError(res, status, why);
                res.set_header("Connection", "close");
                return httplib::Server::HandlerResponse::Handled;
            };
            if (!impl.hostAllowed(req.get_header_value("Host"))) {
                return refuse(403, fmt::format("Host '{}' is not this server's", req.get_header_value("Host").substr(0, 100)));
            }
            if (req.path.rfind("/api/", 0) != 0) return httplib::Server::HandlerResponse::Unhandled;
            const std::string given = req.has_header(kTokenHeader) ? req.get_header_value(kTokenHeader)
                : req.has_param("token")                           ? req.get_param_value("token")
                                                                   : std::string();
            if (!sameSecret(given, impl.options.token)) {
                return refuse(403, "this request lacks the session's token (open the address vxf view printed, with its ?token=)");
            }
            if (req.method != "GET" && req.method != "HEAD") {
                if (req.has_header("Origin") && !impl.originAllowed(req.get_header_value("Origin"))) {
                    return refuse(403, fmt::format("Origin '{}' is not this server's page", req.get_header_value("Origin").substr(0, 100)));
                }
                if (mediaType(req.get_header_value("Content-Type")) != "application/json") {
                    return refuse(415, "a request that changes or writes must send application/json");
                }
            }
            return httplib::Server::HandlerResponse::Unhandled;
        });
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
    }

    /// The page and its scripts, compiled in.
    void serveAssets()
    {
        const auto asset = [this](const char* path, const char* const& body, const char* type) {
            server.Get(
                path, [&body, type](const httplib::Request&, httplib::Response& res) { res.set_content(body, std::strlen(body), type); });
        };
        asset("/", detail::kIndexHtml, "text/html; charset=utf-8");
        asset("/view.js", detail::kViewJs, kJavaScript);
        asset("/three.module.min.js", detail::kThreeJs, kJavaScript);
        asset("/OrbitControls.js", detail::kOrbitControlsJs, kJavaScript);
        asset("/TransformControls.js", detail::kTransformControlsJs, kJavaScript);

        server.Get("/favicon.ico", [](const httplib::Request&, httplib::Response& res) { res.status = 204; });
    }

    /// What the page reads: the file's description, renders, points, slices, the surface and the pipeline.
    void routeReads()
    {
        ViewSession& s = session;
        Impl& impl = *this;
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
            impl.progress.begin();
            try {
                const ViewSession::Rendered r = s.render(impl.options.scene, width, height, impl.options.renderFolder, &impl.progress);
                impl.progress.finish();
                impl.lastPng = r.png;
                sendJson(res, {{"ran", r.ran}, {"seconds", r.seconds}});
            } catch (...) {
                impl.progress.finish();
                throw;
            }
        });
        server.Get("/api/progress", [&impl](const httplib::Request&, httplib::Response& res) { sendJson(res, impl.progress.state()); });
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
        server.Get("/api/volume", [&s](const httplib::Request& req, httplib::Response& res) {
            const long long cells = integerParam(req, "cells", 262144);
            if (cells < 1 || cells > kMaxVolumeCells) {
                throw UsageError(fmt::format("query parameter 'cells': {} is not in [1, {}]", cells, kMaxVolumeCells));
            }
            const VolumeBrick brick = s.brick(param(req, "grid"), std::size_t(cells));
            std::string body;
            append(body, brick.values.data(), brick.values.size());
            res.set_header("X-Vxf-Dims", fmt::format("{},{},{}", brick.dims[0], brick.dims[1], brick.dims[2]));
            res.set_header("X-Vxf-Channels", std::to_string(brick.channels));
            res.set_header("X-Vxf-Cell-Voxels", std::to_string(brick.cellVoxels));
            res.set_header("X-Vxf-World-Min", fmt::format("{},{},{}", brick.worldMin[0], brick.worldMin[1], brick.worldMin[2]));
            res.set_header("X-Vxf-World-Max", fmt::format("{},{},{}", brick.worldMax[0], brick.worldMax[1], brick.worldMax[2]));
            res.set_header("X-Vxf-Min", fmt::format("{}", brick.minValue));
            res.set_header("X-Vxf-Max", fmt::format("{}", brick.maxValue));
            res.set_content(body, "application/octet-stream");
        });
        server.Get("/api/slice", [&s](const httplib::Request& req, httplib::Response& res) {
            const long long axis = integerParam(req, "axis", 2), index = integerParam(req, "index", 0);
            if (axis < 0 || axis > 2) throw UsageError(fmt::format("query parameter 'axis': {} is not 0, 1 or 2", axis));
            const Slice slice = s.slice(param(req, "grid"), int(axis), int(std::clamp<long long>(index, INT32_MIN / 2, INT32_MAX / 2)));
            nlohmann::json values = nlohmann::json::array();
            for (float v : slice.values) values.push_back(std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr));
            sendJson(res,
                {{"axis", slice.axis}, {"index", slice.index}, {"origin", {slice.origin.x(), slice.origin.y(), slice.origin.z()}},
                    {"width", slice.width}, {"height", slice.height}, {"channels", slice.channels}, {"values", values}});
        });
        server.Get("/api/mesh", [&s](const httplib::Request& req, httplib::Response& res) {
            const long long budget = integerParam(req, "triangles", 30000);
            if (budget < 1 || budget > 10'000'000)
                throw UsageError(fmt::format("query parameter 'triangles': {} is not in [1, 1e7]", budget));
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
    }

    /// What changes the session or writes: apply, undo, export.
    void routeEdits()
    {
        ViewSession& s = session;
        server.Post("/api/apply", [&s](const httplib::Request& req, httplib::Response& res) {
            const nlohmann::json body = bodyJson(req);
            const nlohmann::json params = body.contains("params") ? body["params"] : nlohmann::json::object();
            const std::string report = s.apply(stringField(body, "op"), params);
            sendJson(res, {{"report", report}, {"steps", s.steps()}});
        });
        server.Post("/api/undo", [&s](const httplib::Request&, httplib::Response& res) {
            const bool undone = s.undo();
            sendJson(res, {{"undone", undone}, {"steps", s.steps()}, {"redo", s.redoable()}});
        });
        server.Post("/api/redo", [&s](const httplib::Request&, httplib::Response& res) {
            const bool redone = s.redo();
            sendJson(res, {{"redone", redone}, {"steps", s.steps()}, {"redo", s.redoable()}});
        });
        // The history changed as a whole: steps switched off or on, removed, reordered.
        server.Post("/api/steps", [&s](const httplib::Request& req, httplib::Response& res) {
            const nlohmann::json body = bodyJson(req);
            if (!body.contains("steps")) throw UsageError("expected {\"steps\": [{\"op\", \"params\", \"enabled\"}…]}");
            s.setSteps(body["steps"]);
            sendJson(res, {{"steps", s.steps()}, {"redo", s.redoable()}});
        });
        server.Post("/api/export", [&s](const httplib::Request& req, httplib::Response& res) {
            const nlohmann::json body = bodyJson(req);
            const std::string mode = stringField(body, "mode", "whole", false);
            ExportMode m;
            if (mode == "whole")
                m = ExportMode::Whole;
            else if (mode == "diff")
                m = ExportMode::Diff;
            else if (mode == "smoothed")
                m = ExportMode::Smoothed;
            else
                throw UsageError(fmt::format("export mode '{}' is not whole, diff or smoothed", mode));
            int smooth = 2;
            if (body.contains("smooth")) {
                if (!body["smooth"].is_number_integer()) throw UsageError("'smooth' must be a whole number of voxels");
                smooth = body["smooth"].get<int>();
            }
            std::vector<std::string> keep; // whole: the grids written (none named: every grid)
            if (body.contains("grids")) {
                if (!body["grids"].is_array()) throw UsageError("'grids' must be a list of grid names");
                for (const auto& g : body["grids"]) {
                    if (!g.is_string()) throw UsageError("'grids' must be a list of grid names");
                    keep.push_back(g.get<std::string>());
                }
                if (keep.empty()) throw UsageError("'grids' names no grid: the export would hold nothing");
            }
            const std::string written =
                s.exportTo(stringField(body, "path"), m, stringField(body, "grid", "", m != ExportMode::Whole), smooth, keep);
            sendJson(res, {{"written", written}});
        });
        server.set_error_handler([](const httplib::Request& req, httplib::Response& res) {
            if (res.status == 404 && res.body.empty()) sendError(res, 404, fmt::format("no such page or request: {}", req.path));
        });
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
    Impl& impl = *mImpl;
    server.set_payload_max_length(kMaxRequestBytes);
    server.set_read_timeout(kReadTimeoutSeconds);
    server.set_keep_alive_timeout(kKeepAliveSeconds);
    server.new_task_queue = [] { return new httplib::ThreadPool(kWorkerThreads); };
    if (impl.options.token.empty()) impl.options.token = newToken();
    impl.guardRequests();
    impl.serveAssets();
    impl.routeReads();
    impl.routeEdits();
}

ViewServer::~ViewServer() = default;

int ViewServer::bind(const std::string& host, int port)
{
    if (port == 0) {
        port = mImpl->server.bind_to_any_port(host);
        if (port <= 0) throw Error(fmt::format("view: cannot listen on {} (any port)", host));
    } else if (!mImpl->server.bind_to_port(host, port)) {
        throw Error(fmt::format("view: cannot listen on {}:{} (in use? try --port 0)", host, port));
    }
    mImpl->host = host;
    mImpl->port = port;
    return port;
}

const std::string& ViewServer::token() const { return mImpl->options.token; }

void ViewServer::listen() { mImpl->server.listen_after_bind(); }

void ViewServer::stop() { mImpl->server.stop(); }

} // namespace vxf::view
