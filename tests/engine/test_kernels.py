"""The compiled kernels: cached on disk, so a process after the first
compiles nothing; exact signatures, so no call compiles a kernel again."""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from caustic_addon.maps.raster import _accumulate
from caustic_addon.passes.bounce import _branches
from caustic_addon.passes.interface import INTERFACE_TYPES
from caustic_addon.passes.paths import PATH_TYPES
from caustic_addon.scene.material_table import MATERIAL_TYPES
from caustic_addon.tracing.accelerator import GEOMETRY_TYPES
from caustic_addon.tracing.hits import HIT_TYPES
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


# The engine imported as package `engine_copy`, as the add-on imports it under its own name.
RENAMED = """
import importlib.util, sys
spec = importlib.util.spec_from_file_location("engine_copy", "caustic_addon/__init__.py",
                                              submodule_search_locations=["caustic_addon"])
sys.modules["engine_copy"] = module = importlib.util.module_from_spec(spec)
spec.loader.exec_module(module)
"""


def compile_in_a_new_process(folder: Path, script: str = COMPILE, prelude: str = "", engine: Path = REPO) -> dict:
    run = subprocess.run([sys.executable, "-c", prelude + script, str(folder)], cwd=engine, capture_output=True,
                         text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-3000:]
    return json.loads(run.stdout.splitlines()[-1])


def test_the_second_process_loads_a_kernel_from_the_cache(tmp_path):
    first = compile_in_a_new_process(tmp_path)
    second = compile_in_a_new_process(tmp_path)
    assert (first["misses"], first["hits"]) == (1, 0)
    assert (second["misses"], second["hits"]) == (0, 1)
    assert Path(second["folder"]).parent == tmp_path / "caustic_addon"


def test_a_cache_made_in_another_folder_seeds_this_one(tmp_path):
    """The zip carries kernels compiled on the packaging machine; installed,
    the engine sits in another folder, and Blender's user folder starts
    empty. numba's own cache names its folder by a hash of the engine's
    absolute path, where these were never found."""
    for place in ("built", "installed"):
        shutil.copytree(REPO / "caustic_addon", tmp_path / place / "caustic_addon",
                        ignore=shutil.ignore_patterns("__pycache__"))
    compile_in_a_new_process(tmp_path / "shipped", engine=tmp_path / "built")
    seeded = compile_in_a_new_process(tmp_path / "user", COMPILE.replace(
        "jit.use_kernel_cache(sys.argv[1])", f"jit.use_kernel_cache(sys.argv[1], seed={str(tmp_path / 'shipped')!r})"),
        engine=tmp_path / "installed")
    assert (seeded["misses"], seeded["hits"]) == (0, 1)
    assert Path(seeded["folder"]).is_relative_to(tmp_path / "user")


def test_a_seed_copied_where_another_process_has_just_put_its_own_is_dropped(tmp_path):
    """Two Blenders started together on one user folder both seed it: the
    second copy found the first's in place and failed the add-on's
    register (FileExistsError). Now each copy lands whole, in one rename,
    and the later is dropped."""
    shipped, root = tmp_path / "shipped", tmp_path / "user"
    (shipped / "kernel.nbi").parent.mkdir(parents=True)
    (shipped / "kernel.nbi").write_bytes(b"shipped")
    placed = root / "engine" / "digest"
    previous = jit.cache_folder().parents[1]
    try:
        jit.use_kernel_cache(root)
        jit._copy_whole(shipped, placed)
        assert (placed / "kernel.nbi").read_bytes() == b"shipped"
        (placed / "kernel.nbi").write_bytes(b"first")
        jit._copy_whole(shipped, placed)
        assert (placed / "kernel.nbi").read_bytes() == b"first"
        assert [path.name for path in root.iterdir()] == ["engine"]
    finally:
        jit.use_kernel_cache(previous)


def test_each_name_the_engine_is_imported_under_has_a_cache_of_its_own(tmp_path):
    """A cached kernel refers to the modules of the helpers it calls by
    name: the engine imported as another package (the add-on's is
    bl_ext.<repo>.caustics.caustic_addon) shared the CLI's cache, where such
    a kernel failed to load (ModuleNotFoundError: caustic_addon)."""
    compile_in_a_new_process(tmp_path)
    renamed = compile_in_a_new_process(tmp_path, COMPILE.replace("from caustic_addon", "from engine_copy"),
                                       RENAMED)
    assert (renamed["misses"], renamed["hits"]) == (1, 0)
    assert Path(renamed["folder"]).parent == tmp_path / "engine_copy"


def test_the_caches_of_other_engine_sources_are_removed(tmp_path):
    stale = tmp_path / "caustic_addon" / "0123456789abcdef"
    stale.mkdir(parents=True)
    (stale / "old.nbi").write_bytes(b"")
    previous = jit.cache_folder().parents[1]
    try:
        jit.use_kernel_cache(tmp_path)
        assert jit.cache_folder().parent == tmp_path / "caustic_addon"
        assert not stale.exists()
    finally:
        jit.use_kernel_cache(previous)


def test_a_kernel_refuses_arrays_its_signatures_do_not_name():
    """A non-contiguous view would otherwise compile the kernel again, in the middle of a render."""
    acc = np.zeros((1, 4 * 6))
    corners = np.zeros((2, 3, 4))[:, :, :2]
    with pytest.raises(TypeError):
        _accumulate(acc, 4, 4, corners, np.ones((2, 1)))


def test_a_kernel_with_many_arrays_takes_them_by_name_only():
    """A kernel of 16 arguments or more is declared by name (jit.named_kernel):
    its types come from the tables of the fields it takes, and a call that
    passes them by position, or misses or misspells one, is refused before
    anything runs, so two arrays of one type cannot trade places."""
    many = [k.func.__name__ for k in jit._KERNELS if k.func.__code__.co_argcount >= 16 and k.names is None]
    assert not many
    with pytest.raises(TypeError, match="by name only"):
        _branches(*range(36))
    with pytest.raises(TypeError, match="missing: source"):
        _branches(**{name: None for name in _branches.names if name != "source"})
    with pytest.raises(TypeError, match="unknown: sorce"):
        _branches(**{name: None for name in _branches.names if name != "source"}, sorce=None)


def test_a_named_kernel_s_argument_without_a_declared_type_fails_at_its_declaration():
    with pytest.raises(TypeError, match="no table declares the type of 'weight'"):
        jit.named_kernel("void", {"dirs": "f8[:, ::1]"})(lambda dirs, weight: None)


def test_the_field_tables_agree_on_every_name_they_share():
    tables = [PATH_TYPES, HIT_TYPES, INTERFACE_TYPES, MATERIAL_TYPES, GEOMETRY_TYPES]
    for name in set().union(*tables):
        assert len({table[name] for table in tables if name in table}) == 1, name


# Every kernel compiled afresh (cached code cannot be inspected), and what
# its code does per row that it need not. The test runs first in its session
# (conftest.py), and what it compiled seeds the engine's cache.
INSPECT = """
import collections, json, platform, re, sys
from caustic_addon.util import jit
jit.use_kernel_cache(sys.argv[1])
jit.compile_kernels()
counted, helpers = collections.defaultdict(set), collections.defaultdict(set)
for declared in jit._KERNELS:
    name, code = f"{declared.func.__module__}.{declared.func.__name__}", declared.func.__code__
    for result in declared.compiled().overloads.values():
        increfs = collections.Counter(re.findall(r"@NRT_incref\\(ptr %arg\\.(\\w+)\\.0\\)", result.library.get_llvm_str()))
        counted[name].update(arg for arg in code.co_varnames[:code.co_argcount] if increfs[arg] > 1)
        helpers[name].update(re.findall(r"numba_(?:floor|ceil|fmod)", result.library.get_asm_str()))
print(json.dumps({"x86": platform.machine().lower() in ("x86_64", "amd64"),
                  "counted": {k: sorted(v) for k, v in counted.items() if v},
                  "helpers": {k: sorted(v) for k, v in helpers.items() if v}}))
"""


def seed_this_sessions_cache(compiled: Path) -> None:
    """Copy the kernels compiled under `compiled` (a jit cache root) into the
    engine's own cache, each kernel whose index is not there yet: its data
    files first, its index last, each by an atomic rename, so another
    process reading or writing the cache meanwhile sees a kernel whole or
    not at all."""
    source, target = compiled / jit._ENGINE_NAME / jit._DIGEST, jit.cache_folder()
    for index in source.rglob("*.nbi"):
        placed = target / index.relative_to(source)
        if placed.exists():
            continue
        placed.parent.mkdir(parents=True, exist_ok=True)
        for part in sorted(index.parent.glob(index.stem + ".*.nbc")) + [index]:
            partial = placed.parent / f".{part.name}.{os.getpid()}"
            shutil.copyfile(part, partial)
            os.replace(partial, placed.parent / part.name)


@pytest.mark.compiles_every_kernel
def test_no_kernel_takes_an_array_s_reference_again_for_each_row(tmp_path):
    """A kernel takes one atomic reference count of each array it is
    passed, as it starts. An inlined helper that read an array under a
    branch took one more at each call, so at each row: `inside1` did in
    the bounce's `_oriented`, where the two threads fought over the shared
    table of bodies, 5% of an animated pool's frame; so did the curves of
    a Principled layer, the boxes of contacts and the traced vertices of
    a beam grid, and under Python 3.11 the screen layer's views of a
    beam's corners (util.jit.inline). And on x86-64 the kernels round with
    the CPU's own instructions, not calls into numba's helper library."""
    inspected = compile_in_a_new_process(tmp_path, INSPECT)
    seed_this_sessions_cache(tmp_path)
    assert inspected["counted"] == {}
    if inspected["x86"]:
        assert inspected["helpers"] == {}
