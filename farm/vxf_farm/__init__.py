"""vxf farm: the frames of a shot rendered by `vxf run` on a Dask distributed cluster.

`vxf farm SCENE --frames 1-240 --scheduler tcp://HOST:8786` (or `--local N`) submits one task per
frame (or per chunk of frames); each runs the `vxf` binary on a worker over a shared folder.
See docs/farm.md.
"""
