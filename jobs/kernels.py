"""The engine's compiled kernels, made ready before the first render: when
the add-on is enabled, a background thread compiles them into, or loads
them from, the folder it is given (Blender's user folder for the extension,
seeded from the kernels the zip carries); no bpy. A render that starts
sooner waits only for the kernels it calls."""

import threading
from pathlib import Path

from ..caustic_addon import compile_kernels, use_kernel_cache

_warming: threading.Thread | None = None


def start(folder: str | None, shipped: Path) -> None:
    """Compile the kernels on a background thread, cached in `folder`
    (None: the engine's default, its own __pycache__), which takes those
    compiled in `shipped` (the zip's, packaging/ship_kernels.py) first."""
    global _warming
    if folder:
        use_kernel_cache(folder, seed=shipped)
    _warming = threading.Thread(target=compile_kernels, name="Caustics kernels", daemon=True)
    _warming.start()


def compiling() -> bool:
    """Whether the background compile is still going."""
    return _warming is not None and _warming.is_alive()


def wait() -> None:
    """Return once the background compile is done."""
    if _warming is not None:
        _warming.join()
