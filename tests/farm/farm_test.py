"""`vxf farm` on a real Dask cluster on 127.0.0.1 (tests/farm/run starts it): frames identical to
`vxf run --frames` alone, a worker killed mid-frame, a frame with a bad input, a missing frame.

Usage: farm_test.py VXF WORKDIR (the farm's virtual environment: Dask distributed)."""
import glob
import json
import os
import signal
import socket
import subprocess
import sys
import time

VXF, WORK = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
BIN = os.path.dirname(sys.executable)
failures = []


def check(condition, what):
    print(("ok   " if condition else "FAIL ") + what, flush=True)
    if not condition:
        failures.append(what)


def scene(path, width, height, mesh="builtin:sphere", dim=24, material=None):
    """A sphere (or a volume) whose camera and light move over frames 1-4."""
    obj = {"mesh": mesh} if not mesh.endswith(".vdb") else {"volume": mesh}
    obj["material"] = material or {"albedo": 0.9, "mean_free_path": 0.2}
    doc = {
        "objects": [obj],
        "lights": [{"type": "point", "intensity": 3,
                    "position": {"keyframes": [{"frame": 1, "value": [0, 0, 2]}, {"frame": 4, "value": [1.5, 0, 1.5]}]}}],
        "camera": {"position": {"keyframes": [{"frame": 1, "value": [0, -4, 0]}, {"frame": 4, "value": [1, -4, 0.5]}],
                                "interpolation": "bezier"}, "look_at": [0, 0, 0], "fov": 40},
        "voxelize": {"dim": dim},
        "scatter": {"directions": 8, "kernel": "sweep"},
        "render": {"width": width, "height": height, "samples": 1},
        "outputs": ["image"],
    }
    with open(path, "w") as f:
        json.dump(doc, f)
    return path


def vxf_run(scene_path, out):
    subprocess.run([VXF, "run", scene_path, "--frames", "1-4", "--out", out], check=True, stdout=subprocess.DEVNULL)


def farm(*args):
    return subprocess.run([VXF, "farm", *args], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def same_images(a, b, stem):
    def read(path):
        return open(path, "rb").read() if os.path.exists(path) else None
    return all(read(f"{a}/{stem}.{f:04d}.exr") is not None and read(f"{a}/{stem}.{f:04d}.exr") == read(f"{b}/{stem}.{f:04d}.exr")
               for f in range(1, 5))


def leftovers(out):
    return glob.glob(f"{out}/.*.tmp-*") + glob.glob(f"{out}/cache/.*.tmp-*")


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def start_cluster(workers):
    port = free_port()
    address = f"tcp://127.0.0.1:{port}"
    procs = [subprocess.Popen([f"{BIN}/dask", "scheduler", "--host", "127.0.0.1", "--port", str(port), "--no-dashboard"],
                              stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)]
    for i in range(workers):
        procs.append(subprocess.Popen([f"{BIN}/dask", "worker", address, "--nthreads", "1", "--no-nanny", "--no-dashboard",
                                       "--name", f"w{i}", "--host", "127.0.0.1"],
                                      stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    from distributed import Client
    # (A fresh environment's first scheduler can take over a minute to answer under a loaded
    # ctest -j2: CI at 5999997 timed out at 60 s before any test ran.)
    with Client(address, timeout="180s") as client:
        client.wait_for_workers(workers, timeout=120)
    return address, procs


def stop(procs):
    for p in procs:
        if p.poll() is None:
            p.terminate()
    for p in procs:
        try:
            p.wait(timeout=20)
        except subprocess.TimeoutExpired:
            p.kill()


def main():
    os.chdir(WORK)
    s = scene(f"{WORK}/s.json", 48, 36)
    vxf_run(s, f"{WORK}/ref")
    address, procs = start_cluster(2)
    try:
        # 1. Four frames on a scheduler and two workers: the images of `vxf run --frames` alone.
        r = farm(s, "--frames", "1-4", "--scheduler", address, "--out", f"{WORK}/farm")
        print(r.stdout, r.stderr)
        check(r.returncode == 0, "vxf farm --scheduler renders 4 frames (exit 0)")
        check(same_images(f"{WORK}/ref", f"{WORK}/farm", "s"), "the farm's frames are bit-identical to vxf run --frames")
        check("4 of 4 frames done" in r.stdout, "the summary counts 4 frames done")

        # 2. A worker killed during a frame: the frame is rerun on the other and completes.
        slow = scene(f"{WORK}/slow.json", 480, 360, dim=40)
        vxf_run(slow, f"{WORK}/slow-ref")
        out = f"{WORK}/killed"
        job = subprocess.Popen([VXF, "farm", slow, "--frames", "1-4", "--scheduler", address, "--out", out],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        workers = {p.pid for p in procs[1:]}
        victim = None
        deadline = time.monotonic() + 120
        while victim is None and time.monotonic() < deadline and job.poll() is None:
            for line in subprocess.run(["ps", "-eo", "pid=,ppid=,args="], stdout=subprocess.PIPE, text=True).stdout.splitlines():
                pid, ppid, args = line.split(None, 2)
                if int(ppid) in workers and "--out " + out in args and " run " in args:
                    victim = int(ppid)
                    break
            time.sleep(0.05)
        check(victim is not None, "a worker was caught rendering a frame")
        if victim:
            os.kill(victim, signal.SIGKILL)
        stdout, stderr = job.communicate(timeout=600)
        print(stdout, stderr)
        check(job.returncode == 0, "with a worker killed mid-frame, every frame completes (exit 0)")
        check(same_images(f"{WORK}/slow-ref", out, "slow"), "the rerun frame is the frame vxf run renders")
        time.sleep(1)
        check(not leftovers(out), "no partial file left by the killed frame")
    finally:
        stop(procs)

    # 3. A frame whose input is bad: reported with its error while the others finish (--local 2).
    for f in range(1, 5):
        subprocess.run([f"{ROOT}/scripts/make-smoke", f"{WORK}/smoke.{f:04d}.vdb", "--resolution", "16", "--seed", str(f)],
                       check=True, stdout=subprocess.DEVNULL)
    with open(f"{WORK}/smoke.0003.vdb", "r+b") as f:
        f.seek(200)
        f.write(b"\xff" * 64)
    smoke = scene(f"{WORK}/smoke.json", 48, 36, mesh="smoke.$F4.vdb", material={"albedo": 0.9, "mean_free_path": 0.3})
    r = farm(smoke, "--frames", "1-4", "--local", "2", "--retries", "1", "--out", f"{WORK}/smoke-out")
    print(r.stdout, r.stderr)
    check(r.returncode == 1, "a bad frame makes vxf farm exit 1")
    check("3 of 4 frames done" in r.stdout and "frame 3: " in r.stdout, "the summary names the failed frame")
    check("smoke.0003.vdb" in r.stdout.split("frame 3: ")[-1], "the failed frame's error names its file")
    check(all(os.path.exists(f"{WORK}/smoke-out/smoke.{f:04d}.exr") for f in (1, 2, 4)), "the other frames finished")
    check(not os.path.exists(f"{WORK}/smoke-out/smoke.0003.exr") and not leftovers(f"{WORK}/smoke-out"), "no image of the bad frame")

    # 4. A missing frame stops the job before anything is submitted, naming the file.
    os.remove(f"{WORK}/smoke.0004.vdb")
    r = farm(smoke, "--frames", "1-4", "--local", "1", "--out", f"{WORK}/missing")
    check(r.returncode == 1 and "at frame 4" in r.stderr and "smoke.0004.vdb does not exist" in r.stderr,
          "a missing frame is named before submission: " + r.stderr.strip())
    r = farm(smoke, "--frames", "4-1", "--local", "1")
    check(r.returncode == 2 and "the range runs backwards" in r.stderr, "a bad range is a usage error")

    # 5. The OpenCue job (built and checked without a Cuebot): its layer's command, run as RQD
    # runs it with the frame put in, renders the frame vxf run renders.
    r = farm("opencue", s, "--frames", "1-4:2", "--out", f"{WORK}/cue out")
    check(r.returncode == 0, "vxf farm opencue prints a job specification " + r.stderr.strip()[-300:])
    import xml.etree.ElementTree as ET
    spec = ET.fromstring(r.stdout[r.stdout.index("<spec>"):])
    layer = spec.find("job/layers/layer")
    check(layer is not None and layer.findtext("range") == "1,3", "the job's range is OpenCue's form of 1-4:2")
    command = layer.findtext("cmd") if layer is not None else ""
    check("--frames #IFRAME#" in command, "the layer's command takes RQD's frame: " + command)
    subprocess.run(command.replace("#IFRAME#", "3"), shell=True, check=True, stdout=subprocess.DEVNULL)
    check(open(f"{WORK}/cue out/s.0003.exr", "rb").read() == open(f"{WORK}/ref/s.0003.exr", "rb").read(),
          "the OpenCue frame's command renders frame 3 as vxf run does")

    # 6. --quality and --error reach every frame's vxf run (checked first, as vxf run checks them).
    r = farm("opencue", s, "--frames", "1-2", "--out", f"{WORK}/cue q", "--quality", "draft")
    check(r.returncode == 0 and "quality: 'draft'" in r.stdout, "vxf farm opencue --quality says what it chose " + r.stderr[-300:])
    spec = ET.fromstring(r.stdout[r.stdout.index("<spec>"):]) if "<spec>" in r.stdout else None
    command = spec.find("job/layers/layer").findtext("cmd") if spec is not None else ""
    check("--quality draft" in command, "the layer's command asks for the draft quality: " + command)
    r = farm("opencue", s, "--frames", "1", "--error", "5")
    check(r.returncode == 2 and "--error" in r.stderr, "an error out of range is refused before a job: " + r.stderr.strip()[-300:])

    print(f"{len(failures)} failed" if failures else "all passed")
    return 1 if failures else 0


sys.exit(main())
