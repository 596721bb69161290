// vxf — the local HTTP server of `vxf view`: its page, and ViewSession's calls as requests.
#pragma once

#include <vxf/view/ViewSession.h>

#include <memory>
#include <string>

namespace vxf::view {

/// Serves the editor page (embedded: the page, its script and three.js, no network needed) and
/// a JSON/binary API over one ViewSession (cpp-httplib). Requests:
///
/// - GET /api/info: ViewSession::describe(), and "scene" (the scene renders use, or null)
/// - GET /api/points?grid=G&budget=N: binary little-endian float32, per point x y z then 1 or 3
///   values; headers X-Vxf-Count, X-Vxf-Channels, X-Vxf-Cell-Voxels, X-Vxf-Cell-Size,
///   X-Vxf-Min, X-Vxf-Max, X-Vxf-Active
/// - GET /api/volume?grid=G&cells=N: ViewSession::brick, binary float32 per cell its values then
///   its coverage; headers X-Vxf-Dims, X-Vxf-Channels, X-Vxf-Cell-Voxels, X-Vxf-World-Min,
///   X-Vxf-World-Max, X-Vxf-Min, X-Vxf-Max
/// - GET /api/slice?grid=G&axis=A&index=I: JSON axis, index, origin, width, height, channels,
///   values (null where inactive)
/// - GET /api/mesh?triangles=N: binary uint32 vertex count, uint32 triangle count, float32
///   positions, uint32 indices
/// - GET /api/pipeline?output=PATH: ViewSession::pipeline()
/// - POST /api/apply {"op", "params"}: {"report", "steps"}
/// - POST /api/undo, POST /api/redo: {"undone"/"redone", "steps", "redo"}
/// - POST /api/steps {"steps": [{"op", "params", "enabled"}…]}: ViewSession::setSteps, {"steps", "redo"}
/// - POST /api/export {"path", "mode": whole/diff/smoothed, "grid", "smooth", "grids"}: {"written"}
/// - POST /api/render {"width", "height"}: ViewSession::render with the options' scene, {"ran", "seconds"}
/// - GET /api/progress: the render running, {"rendering", "step", "percent", "seconds"}
/// - GET /api/image: the last render's PNG
///
/// Bad requests (unknown grid or operator, malformed JSON, a path outside the served file's
/// folder) are 400 with {"error": message} and change nothing; unknown paths 404.
///
/// Only this machine's pages of this server may use it: every request's Host must be the bound
/// address or a loopback name with the bound port (else 403: DNS rebinding); every /api/ request
/// must carry the session's token (header X-Vxf-Token, or ?token=; else 403), which the page's
/// address holds; a request other than GET must come from no Origin or this server's own (else
/// 403) and send Content-Type application/json (else 415), so a cross-origin form or text/plain
/// POST is refused before it is read. A connection silent for 2 s is closed.
constexpr const char* kTokenHeader = "X-Vxf-Token";

struct ViewServerOptions
{
    std::string scene; ///< a scene file for POST /api/render ("": renders refused)
    std::string renderFolder; ///< where renders are written ("": a folder under the system's temp dir, removed at the end)
    std::string token; ///< the session's secret ("": 128 random bits, as hex)
};

class ViewServer
{
public:
    explicit ViewServer(ViewSession& session, ViewServerOptions options = {});
    ~ViewServer();
    ViewServer(const ViewServer&) = delete;
    ViewServer& operator=(const ViewServer&) = delete;

    /// Bind to @a host:@a port (0: any free port); returns the port. vxf::Error when it cannot.
    int bind(const std::string& host, int port);
    /// The session's secret the API requires (the page's address carries it as ?token=).
    const std::string& token() const;
    /// Serve until stop() (blocks).
    void listen();
    /// Stop listen() (from another thread or a signal handler's thread).
    void stop();

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace vxf::view
