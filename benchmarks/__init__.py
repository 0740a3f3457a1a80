"""The benchmark suite: the kept measurements (this folder's scripts), the
scenes they build (scenes/) and the exact or unbiased references they are
measured against (references/). Scripts import them as packages of the
repository root: `from benchmarks.scenes import ball_lens`."""
