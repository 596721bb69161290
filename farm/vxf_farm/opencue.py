"""`vxf farm opencue`: the frames of a scene as an OpenCue job (PyPI opencue-pyoutline), for studios
whose farm is OpenCue. One Shell layer runs `vxf run SCENE --frames #IFRAME# --out OUT` per frame
(or per --chunk), RQD putting the frame in. Prints the job's specification (what Cuebot takes)
without a Cuebot; --launch submits it to the Cuebot OpenCue's configuration names.
"""
import argparse
import os
import re
import shlex
import sys

from vxf_farm.submit import add_quality_arguments, plan_frames, quality_arguments


def opencue_range(frames):
    """vxf's frame range (A-B:STEP, lists) in OpenCue's syntax (A-BxSTEP)."""
    return ",".join(re.sub(r"^(-?\d+--?\d+):(\d+)$", r"\1x\2", item) for item in frames.split(","))


def job(args):
    import outline
    import outline.cuerun
    import outline.modules.shell

    scene, out = os.path.abspath(args.scene), os.path.abspath(args.out)
    vxf = os.path.abspath(args.vxf) if os.sep in args.vxf else args.vxf
    quality = quality_arguments(args)
    plan_frames(vxf, scene, args.frames, out, quality)  # every frame checked, as vxf run does, before a job exists
    frame_range = opencue_range(args.frames)
    name = args.name or "vxf-" + re.sub(r"[^A-Za-z0-9_]", "_", os.path.splitext(os.path.basename(scene))[0])
    ol = outline.Outline(name, frame_range=frame_range)
    command = shlex.join([vxf, "run", scene, "--frames", "#IFRAME#", "--out", out, *quality]).replace("'#IFRAME#'", "#IFRAME#")
    layer_args = {"command": command, "range": frame_range, "chunk": args.chunk}
    if args.cores:
        layer_args["cores"] = args.cores
    ol.add_layer(outline.modules.shell.Shell("vxf_run", **layer_args))
    return ol


def main(argv=None):
    p = argparse.ArgumentParser(prog="vxf farm opencue", description=__doc__.split("\n\n")[0])
    p.add_argument("scene")
    p.add_argument("--frames", required=True, help="N, A-B, A-B:STEP or a comma-separated list (as vxf run)")
    p.add_argument("--out", default="out", help="output folder, on storage every host shares")
    p.add_argument("--show", default="testing")
    p.add_argument("--shot", default="vxf")
    p.add_argument("--name", help="job name (default vxf-SCENE)")
    p.add_argument("--chunk", type=int, default=1, help="frames per OpenCue frame task (default 1)")
    add_quality_arguments(p)
    p.add_argument("--cores", type=float, help="cores a frame books (default: the shell service's)")
    p.add_argument("--launch", action="store_true", help="submit to Cuebot (else print the job specification)")
    p.add_argument("--vxf", default=os.environ.get("VXF_BINARY", "vxf"), help="the vxf binary, at this path on every host")
    args = p.parse_args(sys.argv[1:] if argv is None else argv)
    import outline.backend.cue
    import outline.cuerun

    ol = job(args)
    if args.launch:
        jobs = outline.cuerun.launch(ol, show=args.show, shot=args.shot, use_pycuerun=False)
        print("vxf farm opencue: submitted", ", ".join(j.name() for j in jobs))
    else:
        launcher = outline.cuerun.OutlineLauncher(ol, show=args.show, shot=args.shot)
        print(outline.backend.cue.serialize_simple(launcher))
    return 0


if __name__ == "__main__":
    sys.exit(main())
