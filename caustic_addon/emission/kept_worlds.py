"""What a render derives from its world, kept while the same world comes
back. Live's updates and an animation's frames read the world again each
time, and deriving a 2048 x 1024 environment's sun, its sky's regions and
its sampling tables again took longer than a Live preview's tracing
(benchmarks/README.md, "Live caustics while the glass is dragged").

A world comes back when its colour is equal and its environment is the
very array it had: the add-on's world bakes and image reads hand the same
array back while the world is unchanged. An environment must therefore not
be written into once rendered (scene.World); the kept entry holds the
array, so no other array can take its id while it is kept."""

from __future__ import annotations

import functools
import threading
from collections import OrderedDict
from typing import Callable, TypeVar

from ..scene import World

T = TypeVar("T")

# Entries kept, over every function: six a world (its sun and sky, the
# sky's regions cut for two or three counts of them, the sampling tables
# of the world and of the sky), for two worlds.
KEPT = 12

_kept: OrderedDict = OrderedDict()
_lock = threading.Lock()


def per_world(derive: Callable[..., T]) -> Callable[..., T]:
    """`derive(world, *args)`, computed once for each world that comes back
    with the same `args` (the last KEPT results of all such functions are
    kept). What it returns is shared: its callers must not change it."""

    @functools.wraps(derive)
    def kept(world: World, *args) -> T:
        environment = world.environment
        key = (derive.__qualname__, world.color.tobytes(), None if environment is None else id(environment), args)
        with _lock:
            if key in _kept:
                _kept.move_to_end(key)
                return _kept[key][1]
        value = derive(world, *args)
        with _lock:
            _kept[key] = (environment, value)
            while len(_kept) > KEPT:
                _kept.popitem(last=False)
        return value

    return kept

