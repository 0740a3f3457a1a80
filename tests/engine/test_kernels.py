"""The compiled kernels: cached on disk, so a process after the first
compiles nothing; exact signatures, so no call compiles a kernel again."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from caustic_addon.maps.raster import _accumulate
from caustic_addon.util import jit

REPO = Path(__file__).resolve().parents[2]
COMPILE = """
import json, sys
from caustic_addon.maps.raster import _accumulate
from caustic_addon.util import jit
jit.use_kernel_cache(sys.argv[1])
stats = _accumulate.compiled().stats
print(json.dumps({"hits": sum(stats.cache_hits.values()), "misses": sum(stats.cache_misses.values()),
                  "folder": str(jit.cache_folder())}))
"""


def compile_in_a_new_process(folder: Path) -> dict:
    run = subprocess.run([sys.executable, "-c", COMPILE, str(folder)], cwd=REPO, capture_output=True, text=True,
                         timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.splitlines()[-1])


def test_the_second_process_loads_a_kernel_from_the_cache(tmp_path):
    first = compile_in_a_new_process(tmp_path)
    second = compile_in_a_new_process(tmp_path)
    assert (first["misses"], first["hits"]) == (1, 0)
    assert (second["misses"], second["hits"]) == (0, 1)
    assert Path(second["folder"]).parent == tmp_path


def test_the_caches_of_other_engine_sources_are_removed(tmp_path):
    stale = tmp_path / "0123456789abcdef"
    stale.mkdir()
    (stale / "old.nbi").write_bytes(b"")
    previous = jit.cache_folder().parent
    try:
        jit.use_kernel_cache(tmp_path)
        assert jit.cache_folder().parent == tmp_path
        assert not stale.exists()
    finally:
        jit.use_kernel_cache(previous)


def test_a_kernel_refuses_arrays_its_signatures_do_not_name():
    """A non-contiguous view would otherwise compile the kernel again, in the middle of a render."""
    acc = np.zeros((1, 4 * 6))
    corners = np.zeros((2, 3, 4))[:, :, :2]
    with pytest.raises(TypeError):
        _accumulate(acc, 4, 4, corners, np.ones((2, 1)))
