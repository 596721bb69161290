"""What a worker runs: `vxf run SCENE --frames F --out OUT` for one frame (or a chunk of frames).

The task is the standard library's subprocess.run on a command line, so the scheduler and the
workers need only Dask and the vxf binary at the same path, not this package (a recent Dask
scheduler unpickles every task: a function of vxf_farm would have to be installed there too).
"""
import subprocess


def frame_command(vxf, scene, frames, out, extra=()):
    """The command line of a task: vxf run for @frames (ints) into @out. setpriv's parent-death
    signal ends vxf when its worker dies (the lost frame is rerun elsewhere, and an orphan would
    race that rerun): SIGTERM, on which vxf removes its temporaries and writes nothing."""
    spec = ",".join(str(f) for f in frames)
    return ["setpriv", "--pdeathsig", "TERM", "--", vxf, "run", scene, "--frames", spec, "--out", out, *extra]


def submit_frames(client, command, key, retries):
    """A future of @command on the cluster: CompletedProcess on success, CalledProcessError
    (its stderr holding vxf's error) when vxf ends with an error."""
    return client.submit(subprocess.run, command, key=key, retries=retries, pure=False, stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE, text=True, check=True)


def failure(error):
    """One line for a failed task: vxf's last line of error, or what ended it."""
    if isinstance(error, subprocess.CalledProcessError):
        lines = [line for line in (error.stderr or "").splitlines() if line.strip()]
        if error.returncode < 0:
            return f"vxf killed by signal {-error.returncode}"
        return lines[-1] if lines else f"vxf exited with status {error.returncode}"
    return f"{type(error).__name__}: {error}"
