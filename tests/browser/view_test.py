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
            page = browser.new_page(viewport={"width": 1200, "height": 760})
            errors = []
            page.on("pageerror", lambda e: errors.append(str(e)))
            started = time.perf_counter()
            page.goto(url)
            page.wait_for_function("window.vxfView && window.vxfView.ready", timeout=60000)
            opened = time.perf_counter() - started
            page.wait_for_timeout(2500)
            fps = page.evaluate("window.vxfView.fps")
            # Points drawn: pixels of the 3D view other than its background (0x1e1f22).
            drawn = page.evaluate("""() => {
                const gl = document.querySelector('#view canvas');
                const c = document.createElement('canvas');
                c.width = gl.width; c.height = gl.height;
                const ctx = c.getContext('2d');
                ctx.drawImage(gl, 0, 0);
                const d = ctx.getImageData(0, 0, c.width, c.height).data;
                let n = 0;
                for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 30) + Math.abs(d[i + 1] - 31) + Math.abs(d[i + 2] - 34) > 30) n++;
                return n;
            }""")
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
            page.click("#select")
            page.wait_for_function("document.querySelector('#status').textContent.startsWith('select:')")
            selected = int(re.search(r"selected (\d+) voxels", page.text_content("#status")).group(1))
            if selected == 0:
                sys.exit("view_test: the brushed box selected no voxel")
            page.fill("#hue", "120")
            page.click("#apply")
            page.wait_for_function("document.querySelector('#status').textContent.startsWith('edit:')")
            page.fill("#exportPath", "page_diff.vdb")
            page.select_option("#exportMode", "diff")
            page.click("#export")
            page.wait_for_function("document.querySelector('#status').textContent.startsWith('wrote')")
            if screenshot:
                page.evaluate("document.getElementById('panel').scrollTop = 0")
                page.screenshot(path=screenshot)
            pipeline = page.evaluate("window.vxfView.call('GET', '/api/pipeline?output=replayed.vdb').then(r => r.json())")
            steps_before = len(pipeline["nodes"])
            hostile_page(browser, url, work)
            after = page.evaluate("window.vxfView.call('GET', '/api/pipeline?output=replayed.vdb').then(r => r.json())")
            if len(after["nodes"]) != steps_before:
                sys.exit("view_test: a page from another origin changed the edit history")
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
    expected = os.path.join(work, "op_diff.vdb")
    run(vxf, "op", "diff", voxels, "-o", expected, "--grid", "colour", "--with", "colour", "--with_file", replayed)
    exported, wanted = grid_values(os.path.join(work, "page_diff.vdb"), "colour_diff"), grid_values(expected, "colour_diff")
    if not wanted or exported != wanted:
        sys.exit(f"view_test: the page's difference ({len(exported)} values) differs from vxf op's ({len(wanted)})")
    print(f"view_test: {selected} voxels selected by brushing and hue-shifted; the exported difference equals vxf op's "
          f"({len(wanted)} voxels); page open in {opened:.2f} s, {fps:.0f} frames per second (software WebGL)")


if __name__ == "__main__":
    main()
