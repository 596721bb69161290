"""The browser test of `vxf view`: headless Chromium (Debian's) driven by Playwright.

Usage: view_test.py VXF WORKDIR [--screenshot PNG]

Voxelizes the bunny (Debian's libcgal-demo), colours it with a gradient, serves it with
`vxf view`, and in the page: waits for the points, checks that they are drawn (pixels other than
the background), brushes a box over the middle of the view, selects it, shifts its hue, exports
the difference. Then replays the pipeline the page recorded with `vxf graph`, makes the
difference with `vxf op diff`, and requires the page's export to equal it bit for bit. Prints the
page's open time and frame rate (measured, not asserted: speed belongs to benchmarks).
"""
import json, os, re, signal, subprocess, sys, tarfile, time

import pyopenvdb as vdb
from playwright.sync_api import sync_playwright

CHROMIUM = os.environ.get("VXF_CHROMIUM", "/usr/bin/chromium")


def run(*cmd):
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        sys.exit(f"view_test: {' '.join(cmd)} failed ({out.returncode}):\n{out.stdout}{out.stderr}")
    return out.stdout


def grid_values(path, name):
    grid = vdb.read(path, name)
    return {(it.min, it.max): tuple(it.value) if hasattr(it.value, "__len__") else it.value for it in grid.citerOnValues()}


def hostile_page(browser, url, work):
    """A page of another origin (another port of 127.0.0.1, as any web page the user visits could
    be) tries what a browser lets it send without asking: text/plain and form POSTs to apply and
    export, with and without the token it cannot know, and a JSON POST (which needs a preflight
    the server does not grant). Nothing may change and nothing may be written."""
    import http.server, threading
    api = re.match(r"(http://[^/]+)/", url).group(1)
    script = f"""<script>
      const api = '{api}';
      const edit = JSON.stringify({{op: 'mul', params: {{grid: 'colour', value: 2}}}});
      const tries = [
        fetch(api + '/api/apply', {{method: 'POST', mode: 'no-cors', headers: {{'Content-Type': 'text/plain'}}, body: edit}}),
        fetch(api + '/api/export', {{method: 'POST', mode: 'no-cors', headers: {{'Content-Type': 'text/plain'}},
                                    body: JSON.stringify({{path: 'evil.vdb', mode: 'whole'}})}}),
        fetch(api + '/api/apply?token=guess', {{method: 'POST', mode: 'no-cors', body: new URLSearchParams({{a: edit}})}}),
        fetch(api + '/api/apply', {{method: 'POST', headers: {{'Content-Type': 'application/json'}}, body: edit}}),
      ];
      Promise.allSettled(tries).then(() => {{ document.title = 'done'; }});
    </script>"""

    class Page(http.server.BaseHTTPRequestHandler):
        def do_GET(self):
            self.send_response(200)
            self.send_header("Content-Type", "text/html")
            self.end_headers()
            self.wfile.write(script.encode())

        def log_message(self, *args):
            pass

    evil = http.server.HTTPServer(("127.0.0.1", 0), Page)
    threading.Thread(target=evil.serve_forever, daemon=True).start()
    try:
        other = browser.new_page()
        other.goto(f"http://127.0.0.1:{evil.server_address[1]}/")
        other.wait_for_function("document.title === 'done'", timeout=20000)
        other.close()
    finally:
        evil.shutdown()
    if os.path.exists(os.path.join(work, "evil.vdb")):
        sys.exit("view_test: a page from another origin wrote a file through vxf view")


def recorded_ops(page):
    pipeline = page.evaluate("window.vxfView.call('GET', '/api/pipeline?output=x.vdb').then(r => r.json())")
    return [node["op"] for node in pipeline["nodes"].values() if "op" in node]


def wait_status(page, prefix):
    """Waits for the status line to start with prefix and returns it, then blanks it: the next wait
    needs a status its own action wrote, not one left from the action before."""
    # 90 s: a render under a loaded CI machine once took longer than 30 (2026-12-07, beside the farm test).
    try:
        page.wait_for_function(f"document.querySelector('#status').textContent.startsWith({json.dumps(prefix)})", timeout=90000)
    except Exception:
        status = page.evaluate("document.querySelector('#status').textContent")
        sys.exit(f"view_test: waited 90 s for a status starting '{prefix}'; the status line says: {status!r}")
    return page.evaluate("(() => { const s = document.querySelector('#status'); const t = s.textContent; s.textContent = ''; return t; })()")


def check_layout(page):
    """At 1280x800 every control lies inside the window: nothing clipped, nothing below the fold."""
    outside = page.evaluate("""() => [...document.querySelectorAll('button, input, select, #steps')]
        .filter((e) => e.offsetParent !== null && getComputedStyle(e).visibility !== 'hidden')
        .map((e) => [e.id || e.className || e.tagName, e.getBoundingClientRect()])
        .filter(([, r]) => r.left < 0 || r.top < 0 || r.right > innerWidth || r.bottom > innerHeight || r.width < 8)
        .map(([name, r]) => `${name} at ${Math.round(r.left)},${Math.round(r.top)} to ${Math.round(r.right)},${Math.round(r.bottom)}`)""")
    if outside:
        sys.exit(f"view_test: at 1280x800 these controls are not wholly in the window: {outside}")


def drawn_pixels(page):
    """Pixels of the 3D view other than its background (0x1e1f22)."""
    # Read inside an animation frame after the page draws one (it draws on demand: the buffer
    # between frames is not the picture).
    return page.evaluate("""() => new Promise((resolve) => { window.vxfView.wake(); requestAnimationFrame(() => {
        const gl = document.querySelector('#view canvas');
        const c = document.createElement('canvas');
        c.width = gl.width; c.height = gl.height;
        const ctx = c.getContext('2d');
        ctx.drawImage(gl, 0, 0);
        const d = ctx.getImageData(0, 0, c.width, c.height).data;
        let n = 0;
        for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 30) + Math.abs(d[i + 1] - 31) + Math.abs(d[i + 2] - 34) > 30) n++;
        resolve(n);
    }); })""")


def volume_view(page):
    """The grid ray-marched as a volume (a 3D texture of its cells) instead of points, a legend
    beside it; then points again."""
    page.select_option("#viewMode", "volume")
    wait_status(page, "colour: a volume of")
    page.wait_for_timeout(1500)
    drawn = drawn_pixels(page)
    if drawn < 5000:
        sys.exit(f"view_test: the ray-marched volume drew {drawn} pixels")
    if not page.is_visible("#legend"):
        sys.exit("view_test: no legend beside the volume")
    fps = page.evaluate("window.vxfView.fps")
    print(f"view_test: the volume drawn ({drawn} pixels, {fps:.0f} frames per second)")
    page.select_option("#viewMode", "points")
    page.wait_for_function("window.vxfView.ready")


def history(page):
    """The history panel: a step switched off is the pipeline without it, on again with it; Ctrl-Z
    undoes the last step and Ctrl-Shift-Z redoes it."""
    if recorded_ops(page) != ["select", "edit"]:
        sys.exit(f"view_test: before the history checks the page recorded {recorded_ops(page)}")
    toggles = page.locator("#steps input[type=checkbox]")
    toggles.nth(1).uncheck()
    wait_status(page, "history: step switched")
    if recorded_ops(page) != ["select"]:
        sys.exit(f"view_test: the hue edit switched off, the pipeline still holds {recorded_ops(page)}")
    # Ctrl-Z pressed while switching the step on is still in flight: the page runs them in order, so
    # the undo takes back the last step (the edit), on again first.
    page.locator("#steps input[type=checkbox]").nth(1).check()
    page.locator("#view canvas").click(position={"x": 5, "y": 5})  # the focus off any field
    page.keyboard.press("Control+z")
    wait_status(page, "undone")
    if recorded_ops(page) != ["select"]:
        sys.exit(f"view_test: Ctrl-Z left {recorded_ops(page)}")
    page.keyboard.press("Control+Shift+z")
    wait_status(page, "redone")
    if recorded_ops(page) != ["select", "edit"]:
        sys.exit(f"view_test: Ctrl-Shift-Z left {recorded_ops(page)}")


def paint_stroke(page, work):
    """Paint on: a drag over the bunny lays one `paint` step on the first visible voxels under the
    cursor (not through the object); the set exported whole after it, and the pipeline then."""
    page.select_option("#grid", "colour")
    page.wait_for_function("window.vxfView.ready && window.vxfView.cloud && window.vxfView.cloud.count > 0")
    voxel = page.evaluate("window.vxfView.info.grids.find((g) => g.name === 'colour').voxel_size")
    page.check("#paintMode")
    page.fill("#paintRadius", str(2 * voxel))  # two voxels
    box = page.locator("#view canvas").bounding_box()
    cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
    page.mouse.move(cx - 40, cy)
    page.mouse.down()
    page.mouse.move(cx + 40, cy, steps=12)
    page.mouse.up()
    report = wait_status(page, "paint:")
    match = re.search(r"painted (\d+) voxels of 'colour' \((\d+) points\)", report)
    if not match:
        sys.exit(f"view_test: the stroke reported {report!r}")
    voxels, points = int(match.group(1)), int(match.group(2))
    # Each point's brush holds at most (4/3)π·2³ ≈ 34 voxels: a stroke through the whole object
    # (the old brush selected 1,859 voxels for 101 points) would paint far more.
    if voxels == 0 or voxels > points * 34:
        sys.exit(f"view_test: {points} brush points painted {voxels} voxels")
    page.uncheck("#paintMode")
    page.fill("#exportPath", "painted.vdb")
    page.select_option("#exportMode", "whole")
    page.click("#export")
    wait_status(page, "wrote")
    pipeline = page.evaluate("window.vxfView.call('GET', '/api/pipeline?output=x.vdb').then(r => r.json())")
    page.click("#undo")
    wait_status(page, "undone")
    return os.path.join(work, "painted.vdb"), pipeline


def float_edit(page):
    """A float grid (the bunny's density) set on the selection, then undone."""
    page.select_option("#grid", "density")
    if page.is_visible("#hue") or not page.is_visible("#setValue"):
        sys.exit("view_test: a float grid shown, the edit panel still offers colours")
    page.check("#doSetValue")
    page.fill("#setValue", "0.5")
    page.click("#apply")
    report = wait_status(page, "edit:")
    if "changed" not in report:
        sys.exit(f"view_test: the density edit reported {report}")
    page.click("#undo")
    wait_status(page, "undone")


def handles(page):
    """The selection box dragged by its handle (three.js TransformControls): moved from its centre,
    the box's fields follow with its size kept; the slice plane dragged along its axis moves the
    slice."""
    page.fill("#minX", "-0.02"); page.fill("#minY", "-0.02"); page.fill("#minZ", "-0.02")
    page.fill("#maxX", "0.02"); page.fill("#maxY", "0.02"); page.fill("#maxZ", "0.02")
    page.dispatch_event("#maxZ", "change")
    page.select_option("#handle", "move")
    canvas = page.locator("#view canvas").bounding_box()

    def on_screen(point):
        x, y = page.evaluate("""(p) => { const v = new window.vxfView.THREE.Vector3(...p).project(window.vxfView.camera);
            const c = document.querySelector('#view canvas'); return [(v.x + 1) / 2 * c.clientWidth, (1 - v.y) / 2 * c.clientHeight]; }""", point)
        return canvas["x"] + x, canvas["y"] + y

    def drag(start, dx, dy):
        page.mouse.move(*start)
        page.mouse.down()
        page.mouse.move(start[0] + dx, start[1] + dy, steps=8)
        page.mouse.up()

    fields = lambda ids: [float(page.input_value(f"#{i}")) for i in ids]
    drag(on_screen([0, 0, 0]), 60, 0)  # the centre: free translation in the view's plane
    lo, hi = fields(["minX", "minY", "minZ"]), fields(["maxX", "maxY", "maxZ"])
    if not lo[0] > -0.02 + 1e-3 or any(abs((h - l) - 0.04) > 1e-4 for l, h in zip(lo, hi)):
        sys.exit(f"view_test: the box dragged by its handle is {lo} to {hi}")
    page.locator("#view canvas").click(position={"x": 5, "y": 5})
    page.keyboard.press("s")  # the slice plane's handle: an arrow along the slice's axis (z)
    if page.input_value("#handle") != "slice":
        sys.exit("view_test: S did not take the slice plane's handle")
    index = int(page.input_value("#sliceIndex"))
    origin = page.evaluate("window.vxfView.handlePosition()")
    # Grab the arrow halfway along it: the gizmo keeps a constant size on screen.
    tip = page.evaluate("window.vxfView.handleAxisPoint(2, 0.3)")
    drag(on_screen(tip), 0, -40)
    page.wait_for_function(f"document.querySelector('#sliceIndex').value != '{index}'", timeout=10000)
    moved = page.evaluate("window.vxfView.handlePosition()")
    if not moved[2] > origin[2]:
        sys.exit(f"view_test: the slice plane dragged up moved from {origin} to {moved}")
    page.select_option("#handle", "")


def render_shows_hue(browser, vxf, work):
    """With --scene, a select + hue edit of the scattered light, then Render: the image shows the hue
    (the render once dropped edits made after a re-run of the scatter)."""
    scene = {"objects": [{"mesh": "bunny00.off", "material": {"albedo": [0.95, 0.35, 0.2], "mean_free_path": 0.02}}],
             "lights": [{"type": "point", "position": [0.3, -0.4, 0.5], "intensity": 4.0}],
             "camera": {"position": [0.0, -0.45, 0.15], "look_at": [0, 0, 0.0], "up": [0, 0, 1], "fov": 35}}
    with open(os.path.join(work, "lit.json"), "w") as f:
        json.dump(scene, f)
    run(vxf, "voxelize", os.path.join(work, "bunny00.off"), "-o", os.path.join(work, "v32.vdb"), "--dim", "32", "-q")
    run(vxf, "light", os.path.join(work, "v32.vdb"), "-o", os.path.join(work, "l32.vdb"), "--scene", os.path.join(work, "lit.json"))
    run(vxf, "scatter", os.path.join(work, "l32.vdb"), "-o", os.path.join(work, "s32.vdb"))
    server = subprocess.Popen([vxf, "view", os.path.join(work, "s32.vdb"), "--no-browser", "--port", "0", "--grid", "scatter",
                               "--scene", os.path.join(work, "lit.json")], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        url = re.search(r"at (http://\S+)", server.stdout.readline()).group(1)
        page = browser.new_page(viewport={"width": 1280, "height": 800})
        page.goto(url)
        page.wait_for_function("window.vxfView && window.vxfView.ready", timeout=60000)

        def render():
            page.fill("#renderWidth", "96")
            page.fill("#renderHeight", "72")
            page.click("#render")
            wait_status(page, "rendered")
            page.wait_for_function("document.querySelector('#renderImage').complete && document.querySelector('#renderImage').naturalWidth > 0")
            return page.evaluate("""() => { const img = document.querySelector('#renderImage');
                const c = document.createElement('canvas'); c.width = img.naturalWidth; c.height = img.naturalHeight;
                const ctx = c.getContext('2d'); ctx.drawImage(img, 0, 0);
                const d = ctx.getImageData(0, 0, c.width, c.height).data; const sum = [0, 0, 0];
                for (let i = 0; i < d.length; i += 4) for (let k = 0; k < 3; k++) sum[k] += d[i + k];
                return sum; }""")

        before = render()
        for field, value in zip(["minX", "minY", "minZ", "maxX", "maxY", "maxZ"], [-10, -10, -10, 10, 10, 10]):
            page.fill(f"#{field}", str(value))
        page.click("#select")
        wait_status(page, "select:")
        page.fill("#hue", "120")
        page.click("#apply")
        wait_status(page, "edit:")
        after = render()
        page.close()
    finally:
        server.terminate()
        server.wait(timeout=30)
    # Red-orange light turned 120° is green: green over red grows several times.
    ratio = lambda s: s[1] / max(s[0], 1)
    if not ratio(after) > 2 * ratio(before):
        sys.exit(f"view_test: after a hue shift of the scatter the render's RGB sums are {after} (before {before})")
    print(f"view_test: the render after select + hue shows the hue (RGB sums {before} -> {after})")


def main():
    vxf, work = sys.argv[1], sys.argv[2]
    screenshot = sys.argv[sys.argv.index("--screenshot") + 1] if "--screenshot" in sys.argv else None
    os.makedirs(work, exist_ok=True)
    if not os.path.exists(CHROMIUM):
        sys.exit(f"view_test: no Chromium at {CHROMIUM} (scripts/install-deps installs Debian's)")
    with tarfile.open("/usr/share/doc/libcgal-dev/data.tar.gz") as tar:
        member = tar.getmember("data/meshes/bunny00.off")
        member.name = "bunny00.off"
        tar.extract(member, work)
    voxels = os.path.join(work, "bunny.vdb")
    run(vxf, "voxelize", os.path.join(work, "bunny00.off"), "-o", voxels, "--dim", "64", "-q")
    run(vxf, "op", "gradient", voxels, "-o", voxels, "--from", "-0.1,0,0", "--to", "0.1,0,0",
        "--colors", "0.9,0.2,0.1;0.1,0.4,0.9", "--out", "colour")

    server = subprocess.Popen([vxf, "view", voxels, "--no-browser", "--port", "0", "--grid", "colour"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        line = server.stdout.readline()
        match = re.search(r"at (http://\S+)", line)
        if not match:
            sys.exit(f"view_test: vxf view printed no address: {line!r} {server.stderr.read()}")
        url = match.group(1)
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM,
                                        args=["--no-sandbox", "--use-angle=swiftshader", "--enable-unsafe-swiftshader"])
            page = browser.new_page(viewport={"width": 1280, "height": 800})
            errors = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            started = time.perf_counter()
            page.goto(url)
            page.wait_for_function("window.vxfView && window.vxfView.ready", timeout=60000)
            opened = time.perf_counter() - started
            page.wait_for_timeout(2500)
            fps = page.evaluate("window.vxfView.fps")
            drawn = drawn_pixels(page)  # the points
            if drawn < 5000:
                sys.exit(f"view_test: only {drawn} pixels of the view differ from its background: no points drawn")

            # Brush a box over the middle of the view, select what it holds, shift its hue.
            box = page.locator("#view canvas").bounding_box()
            cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
            before = page.input_value("#minX")
            page.keyboard.down("Shift")
            page.mouse.move(cx - 90, cy - 70)
            page.mouse.down()
            page.mouse.move(cx + 10, cy + 60, steps=5)
            page.mouse.up()
            page.keyboard.up("Shift")
            if page.input_value("#minX") == before:
                sys.exit(f"view_test: brushing set no box ({page.text_content('#status')})")
            check_layout(page)
            volume_view(page)
            # A brush released over the panel ends there (it stuck to the mouse).
            page.keyboard.down("Shift")
            page.mouse.move(cx - 60, cy - 40)
            page.mouse.down()
            page.mouse.move(box["x"] - 100, cy, steps=4)
            page.mouse.up()
            page.keyboard.up("Shift")
            page.mouse.move(cx, cy + 50)
            if page.evaluate("getComputedStyle(document.getElementById('brush')).display") != "none":
                sys.exit("view_test: a brush released over the panel is still drawn")
            page.keyboard.down("Shift")  # the box the test selects, again
            page.mouse.move(cx - 90, cy - 70)
            page.mouse.down()
            page.mouse.move(cx + 10, cy + 60, steps=5)
            page.mouse.up()
            page.keyboard.up("Shift")
            page.click("#select")
            selected = int(re.search(r"selected (\d+) voxels", wait_status(page, "select:")).group(1))
            if selected == 0:
                sys.exit("view_test: the brushed box selected no voxel")
            page.fill("#hue", "120")
            page.click("#apply")
            wait_status(page, "edit:")
            page.fill("#exportPath", "page_diff.vdb")
            page.select_option("#exportMode", "diff")
            page.click("#export")
            wait_status(page, "wrote")
            if screenshot:
                page.evaluate("document.getElementById('panel').scrollTop = 0")
                page.screenshot(path=screenshot)
            history(page)
            pipeline = page.evaluate("window.vxfView.call('GET', '/api/pipeline?output=replayed.vdb').then(r => r.json())")
            steps_before = len(pipeline["nodes"])
            hostile_page(browser, url, work)
            after = page.evaluate("window.vxfView.call('GET', '/api/pipeline?output=replayed.vdb').then(r => r.json())")
            if len(after["nodes"]) != steps_before:
                sys.exit("view_test: a page from another origin changed the edit history")
            float_edit(page)
            painted, paint_pipeline = paint_stroke(page, work)
            handles(page)
            render_shows_hue(browser, vxf, work)
            if errors:
                sys.exit(f"view_test: the page raised: {errors}")
            browser.close()
    finally:
        server.send_signal(signal.SIGINT)
        try:
            rest, err = server.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            server.kill()
            sys.exit("view_test: vxf view did not stop on Ctrl-C")
    if server.returncode != 0 or "stopped" not in rest:
        sys.exit(f"view_test: vxf view exited {server.returncode} on Ctrl-C: {rest}{err}")

    # The recorded pipeline, replayed by `vxf graph`, and the difference `vxf op diff` makes of it.
    replayed = os.path.join(work, "replayed.vdb")
    pipeline["outputs"] = {name: replayed for name in pipeline["outputs"]}
    with open(os.path.join(work, "pipeline.json"), "w") as out:
        json.dump(pipeline, out)
    ops = [node["op"] for node in pipeline["nodes"].values() if "op" in node]
    if ops != ["select", "edit"]:
        sys.exit(f"view_test: the page recorded {ops}, expected select then edit")
    run(vxf, "graph", os.path.join(work, "pipeline.json"))
    # The stroke replayed by the operator itself (vxf graph runs `paint`): the same voxels and values.
    repainted = os.path.join(work, "repainted.vdb")
    paint_pipeline["outputs"] = {name: repainted for name in paint_pipeline["outputs"]}
    with open(os.path.join(work, "paint_pipeline.json"), "w") as out:
        json.dump(paint_pipeline, out)
    run(vxf, "graph", os.path.join(work, "paint_pipeline.json"))
    if grid_values(painted, "colour") != grid_values(repainted, "colour"):
        sys.exit("view_test: the page's painted colour differs from what the paint operator makes of its stroke")
    expected = os.path.join(work, "op_diff.vdb")
    run(vxf, "op", "diff", voxels, "-o", expected, "--grid", "colour", "--with", "colour", "--with_file", replayed)
    exported, wanted = grid_values(os.path.join(work, "page_diff.vdb"), "colour_diff"), grid_values(expected, "colour_diff")
    if not wanted or exported != wanted:
        sys.exit(f"view_test: the page's difference ({len(exported)} values) differs from vxf op's ({len(wanted)})")
    print(f"view_test: {selected} voxels selected by brushing and hue-shifted; the exported difference equals vxf op's "
          f"({len(wanted)} voxels); page open in {opened:.2f} s, {fps:.0f} frames per second (software WebGL)")


if __name__ == "__main__":
    main()
