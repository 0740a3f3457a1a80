"""Compiled kernels: the per-ray loops between Embree's casts, in numba's
nopython mode without the GIL, so the pass's thread pool keeps both cores
busy (numba's own parallel regions are never used: they are not safe when
several Python threads start them).

A kernel is an ordinary Python function over arrays, declared with its
signatures:

    @kernel("void(f8[:, ::1], f8[::1])")
    def scale_rows(rows, by): ...

It compiles on its first call, or ahead of it with `compile_kernels()`, and is
cached on disk, so a process compiles it once per Python and engine source:
in `use_kernel_cache()`'s folder (the add-on passes Blender's user folder for
the extension, seeded from the kernels its zip carries) or, by default, in
this package's `__pycache__`. The cache is kept apart by the name the
engine is imported under (a cached kernel refers to its module by that
name: `caustic_addon` for the CLI and the engine's tests,
`bl_ext.<repo>.caustics.caustic_addon` in Blender), and by a digest of the
engine's source, since numba would not see an edit to a function that a
kernel calls from another module. Inside, a kernel's files sit by its
module's folder in the engine, so that a cache made in another place (the
zip's) is found. Kernels are compiled for the oldest CPU of the platform
that Blender runs on (set for the whole process unless it was set
before), not for this machine's, so one cache serves every machine of a
platform: on x86-64 that is x86-64-v2, SSE4.2 and what comes with it,
which Blender requires since 4.2 (its creator_cpu_check.cc); elsewhere
numba's "generic". numba's generic x86-64 has no SSE4.1 rounding, so
each floor and fmod would be a call into numba's helper library. Arrays
must match the signature exactly (`f8[:, ::1]` is C-contiguous float64): a
kernel never compiles again for other types.

Scalar helpers that kernels call (`@inline`) are inlined into each kernel."""

from __future__ import annotations

import functools
import hashlib
import inspect
import os
import platform
import shutil
import sys
import threading
from pathlib import Path

import numba
from numba.core import caching

_ENGINE = Path(__file__).resolve().parents[1]
_ENGINE_NAME = __name__.rpartition(".util.")[0]
_KERNELS: list["Kernel"] = []
_lock = threading.RLock()
_cache_root = _ENGINE / "__pycache__" / "kernels"
_pruned: Path | None = None


def _source_digest() -> str:
    """The first 16 hex digits of a SHA-256 over the engine's .py files."""
    digest = hashlib.sha256()
    for path in sorted(_ENGINE.rglob("*.py")):
        digest.update(path.relative_to(_ENGINE).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


_DIGEST = _source_digest()


def use_kernel_cache(folder: str | Path, seed: str | Path | None = None) -> None:
    """Cache the kernels compiled from now on in `folder`, under folders
    named by the engine's import name and source digest; where it has no
    kernels of this engine yet, those compiled in the cache folder `seed`
    (the zip's) are copied into it first."""
    global _cache_root
    with _lock:
        _cache_root = Path(folder)
        shipped = None if seed is None else Path(seed) / _ENGINE_NAME / _DIGEST
        if shipped is not None and shipped.is_dir() and not cache_folder().is_dir():
            _copy_whole(shipped, cache_folder())


def _copy_whole(source: Path, target: Path) -> None:
    """Copy the folder `source` to `target` in one rename, so that another
    process seeding the same folder at the same time (two Blenders started
    together on one user folder) never reads half a copy, nor fails on the
    other's; the later of the two copies is dropped."""
    partial = _cache_root / f".seeding-{os.getpid()}-{threading.get_ident()}"
    shutil.copytree(source, partial, dirs_exist_ok=True)
    target.parent.mkdir(parents=True, exist_ok=True)
    try:
        os.rename(partial, target)
    except OSError:
        shutil.rmtree(partial, ignore_errors=True)


def cache_folder() -> Path:
    """The folder the kernels compiled now are cached in; the first time
    a folder is asked for, the caches of other sources of the engine under
    this name beside it are removed."""
    global _pruned
    named = _cache_root / _ENGINE_NAME
    if named != _pruned and named.is_dir():
        for stale in named.iterdir():
            if stale.is_dir() and stale.name != _DIGEST:
                shutil.rmtree(stale, ignore_errors=True)
    _pruned = named
    return named / _DIGEST


class Kernel:
    """A kernel compiled on first use: `func` under numba.njit(signatures,
    nogil=True, cache=True). A kernel with `names` (named_kernel) is called
    with its arguments by those names only."""

    def __init__(self, func, signatures: tuple[str, ...], names: tuple[str, ...] | None = None):
        self.func, self.signatures, self.names = func, signatures, names
        self._compiled = None
        functools.update_wrapper(self, func)

    def compiled(self):
        """The numba dispatcher, compiled, or loaded from the cache, on first use."""
        if self._compiled is None:
            with _lock:
                if self._compiled is None:
                    self._compiled = _njit_cached(self.func, self.signatures)
        return self._compiled

    def __call__(self, *args, **named):
        if self.names is None:
            return self.compiled()(*args)
        missing, unknown = [n for n in self.names if n not in named], sorted(set(named) - set(self.names))
        if args or missing or unknown:
            raise TypeError(f"{self.func.__name__} takes its arguments by name only"
                            + (f"; missing: {', '.join(missing)}" if missing else "")
                            + (f"; unknown: {', '.join(unknown)}" if unknown else ""))
        return self.compiled()(*(named[n] for n in self.names))


def _njit_cached(func, signatures: tuple[str, ...]):
    """numba.njit, cached by _EngineCacheLocator."""
    return numba.njit(list(signatures), nogil=True, cache=True)(func)


class _EngineCacheLocator(caching._CacheLocator):
    """Where numba caches a kernel of this engine: in cache_folder(), in the
    folder of the kernel's module inside the engine, its stamp the engine's
    digest. numba's own locators name the folder by a hash of the module's
    absolute path and stamp it with the file's contents (0.62: its time), so
    a cache made in another place would never be found."""

    def __init__(self, py_func, py_file: str):
        self._lineno = py_func.__code__.co_firstlineno
        self._path = cache_folder() / Path(py_file).resolve().parent.relative_to(_ENGINE)

    def get_cache_path(self) -> str:
        return str(self._path)

    def get_source_stamp(self) -> str:
        return _DIGEST

    def get_disambiguator(self) -> str:
        return str(self._lineno)

    @classmethod
    def from_function(cls, py_func, py_file: str):
        """The locator of a kernel of this engine under this import name,
        or None: numba then asks the next locator (an import of the engine
        under another name has its own)."""
        if not py_func.__module__.startswith(_ENGINE_NAME + "."):
            return None
        locator = cls(py_func, py_file)
        try:
            locator.ensure_cache_path()
        except OSError:
            return None
        return locator


caching.CacheImpl._locator_classes.insert(0, _EngineCacheLocator)
if numba.config.CPU_NAME is None:
    numba.config.CPU_NAME = "x86-64-v2" if platform.machine().lower() in ("x86_64", "amd64") else "generic"
    numba.config.CPU_FEATURES = ""


def kernel(*signatures: str):
    """Declare a compiled kernel with its numba `signatures`."""
    def declare(func) -> Kernel:
        made = Kernel(func, signatures)
        _KERNELS.append(made)
        return made
    return declare


def named_kernel(returns: str, *tables: dict[str, str]):
    """Declare a compiled kernel whose arguments are typed by name: each
    parameter takes its numba type from the first of `tables` that names it
    (the path state's, the hits', ... each declared once beside its
    fields), an `out_<field>` parameter its field's type; the signature is
    `returns` of those types in the parameters' order. The kernel is then
    called with every argument by name, so two arrays of one type cannot
    trade places; a parameter no table types fails at import."""
    def declare(func) -> Kernel:
        names = tuple(inspect.signature(func).parameters)
        types = []
        for name in names:
            typed = [table[key] for key in (name, name.removeprefix("out_")) for table in tables if key in table]
            if not typed:
                raise TypeError(f"kernel {func.__name__}: no table declares the type of '{name}'")
            types.append(typed[0])
        made = Kernel(func, (f"{returns}({', '.join(types)})",), names)
        _KERNELS.append(made)
        return made
    return declare


def inline(func):
    """A scalar helper for kernels, inlined into each kernel that calls it
    in numba's own IR: a call to a compiled function takes an atomic
    reference count of each array it is passed, which both threads'
    kernels contend for on a shared table. Inlined, a helper still takes
    one where it reads an array under a branch or in a loop, so helpers
    read arrays unconditionally (tracing.accelerator.inside1) or leave the
    reading to their kernel (optics.principled.curve_at1)."""
    return numba.njit(nogil=True, inline="always")(func)


def kernels_cached() -> bool:
    """Whether every kernel declared so far is in the cache for this
    Python, so that compile_kernels() only loads them (numba names a
    kernel's index file <name>-<line>.py<major><minor>.nbi)."""
    folder = cache_folder()
    python = f"py{sys.version_info.major}{sys.version_info.minor}"
    return folder.is_dir() and sum(1 for _ in folder.rglob(f"*.{python}.nbi")) >= len(_KERNELS)


def compile_kernels() -> int:
    """Compile (or load from the cache) every kernel declared so far;
    returns how many there are. Importing the engine (`caustic_addon`)
    imports every pass, so every kernel is declared by then."""
    for declared in list(_KERNELS):
        declared.compiled()
    return len(_KERNELS)
