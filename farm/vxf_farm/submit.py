"""`vxf farm`: submit a shot's frames to a Dask cluster, follow them, and summarise."""
import argparse
import os
import subprocess
import sys
import time

from dask import config as dask_config
from distributed import Client, LocalCluster, as_completed

from vxf_farm import tasks


def parse_args(argv):
    p = argparse.ArgumentParser(
        prog="vxf farm",
        description="Render the frames of a scene (vxf run --frames) on a Dask distributed cluster: one task per frame "
        "(or per --chunk frames) runs the vxf binary on a worker, reading and writing a folder every worker shares. "
        "Failed or lost frames are retried; the summary names every frame that still failed, with its error.",
    )
    p.add_argument("scene", help="scene file (on the shared folder)")
    p.add_argument("--frames", required=True, help="N, A-B, A-B:STEP or a comma-separated list (as vxf run)")
    p.add_argument("--out", default="out", help="output folder on the shared folder (default: out)")
    where = p.add_mutually_exclusive_group(required=True)
    where.add_argument("--scheduler", help="a running Dask scheduler, tcp://HOST:8786 (workers: docs/farm.md)")
    where.add_argument("--local", type=int, metavar="N", help="start a cluster of N workers on this machine")
    p.add_argument("--retries", type=int, default=2, help="times a failed or lost frame is tried again (default 2)")
    p.add_argument("--chunk", type=int, default=1, help="frames per task (default 1)")
    p.add_argument("--warm-start", action="store_true", help="within a chunk, each frame's scatter starts from the frame before's")
    add_quality_arguments(p)
    p.add_argument("--vxf", default=os.environ.get("VXF_BINARY", "vxf"), help="the vxf binary, at the same path on every worker")
    args = p.parse_args(argv)
    if args.retries < 0:
        p.error(f"--retries is {args.retries}: expected 0 or more")
    if args.chunk < 1:
        p.error(f"--chunk is {args.chunk}: expected 1 or more")
    if args.local is not None and args.local < 1:
        p.error(f"--local is {args.local}: expected 1 or more workers")
    return args


def add_quality_arguments(parser):
    """--error / --quality, passed to every frame's vxf run (vxf run --help says what they do)."""
    quality = parser.add_mutually_exclusive_group()
    quality.add_argument("--error", help="the error wanted, as vxf run --error (0.001-1): every frame gets the setting chosen for it")
    quality.add_argument("--quality", choices=["draft", "final", "reference"], help="a level naming an error, as vxf run --quality")


def quality_arguments(args):
    """The vxf run arguments of --error / --quality (none when neither is given)."""
    return ["--error", args.error] if args.error else ["--quality", args.quality] if args.quality else []


def plan_frames(vxf, scene, frames, out, extra=()):
    """The frames, as `vxf run --dry-run` lists them after checking every frame's scene and
    inputs (a bad range or a missing frame stops here, before anything is submitted); @a extra:
    vxf run's arguments every frame takes (checked too)."""
    done = subprocess.run([vxf, "run", scene, "--frames", frames, "--out", out, "--dry-run", *extra], stdout=subprocess.PIPE,
                          stderr=subprocess.PIPE, text=True)
    if done.returncode != 0:
        sys.stderr.write(done.stderr)
        raise SystemExit(done.returncode)
    for line in done.stdout.splitlines():
        if line.startswith("quality: "):  # what --error / --quality (or the scene's quality) chose, and why
            print(f"vxf farm: {line}", flush=True)
    return [int(line.split()[1].rstrip(":")) for line in done.stdout.splitlines() if line.startswith("frame ")]


def duration(seconds):
    seconds = int(round(seconds))
    return f"{seconds // 3600}h{seconds // 60 % 60:02d}m{seconds % 60:02d}s" if seconds >= 3600 else f"{seconds // 60}m{seconds % 60:02d}s"


def follow(client, futures, chunks, total):
    """Print progress as frames end; the failed chunks' errors, by their first frame."""
    start = time.monotonic()
    done, failed = 0, {}
    for future in as_completed(futures):
        frames = chunks[future.key]
        named = f"frame{'s' if len(frames) > 1 else ''} {','.join(map(str, frames))}"
        if future.status == "finished":
            done += len(frames)
            where = client.who_has([future]).get(future.key) or ["?"]
            what = f"{named} done on {where[0]}"
        else:
            error = tasks.failure(future.exception())
            for f in frames:
                failed[f] = error
            what = f"{named} FAILED: {error}"
        finished = done + len(failed)
        # (a worker holds the tasks it was given: those beyond its threads wait there)
        running = min(sum(len(keys) for keys in client.processing().values()), sum(client.nthreads().values()))
        elapsed = time.monotonic() - start
        eta = elapsed / finished * (total - finished) if finished else 0.0
        print(f"[{finished}/{total}] {what} | done {done}, failed {len(failed)}, running {running}, ETA {duration(eta)}", flush=True)
    return done, failed, time.monotonic() - start


def main(argv=None):
    args = parse_args(sys.argv[1:] if argv is None else argv)
    scene, out = os.path.abspath(args.scene), os.path.abspath(args.out)
    if os.sep in args.vxf:
        args.vxf = os.path.abspath(args.vxf)
    quality = quality_arguments(args)
    frames = plan_frames(args.vxf, scene, args.frames, out, quality)
    extra = (["--warm-start"] if args.warm_start else []) + quality
    # A frame that kills its worker (lost, out of memory) counts against the same retries.
    dask_config.set({"distributed.scheduler.allowed-failures": args.retries})
    if args.local is not None:
        cluster = LocalCluster(n_workers=args.local, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    else:
        cluster = None
        client = Client(args.scheduler, timeout="30s")
    try:
        workers = len(client.scheduler_info()["workers"])
        print(f"vxf farm: {len(frames)} frames of {args.scene} on {workers} worker{'s' if workers != 1 else ''} "
              f"({'local' if cluster else args.scheduler}), {args.chunk} a task, {args.retries} retries", flush=True)
        futures, chunks = [], {}
        for i in range(0, len(frames), args.chunk):
            chunk = frames[i:i + args.chunk]
            key = f"vxf-frames-{chunk[0]}-{os.getpid()}-{time.time_ns()}"
            future = tasks.submit_frames(client, tasks.frame_command(args.vxf, scene, chunk, out, extra), key, args.retries)
            futures.append(future)
            chunks[future.key] = chunk
        done, failed, seconds = follow(client, futures, chunks, len(frames))
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    print(f"vxf farm: {done} of {len(frames)} frames done in {duration(seconds)}" + (f", {len(failed)} failed:" if failed else ""))
    for frame in sorted(failed):
        print(f"  frame {frame}: {failed[frame]}")
    return 1 if failed else 0
