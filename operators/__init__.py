"""The add-on's operators: thin layers between Blender and the engine."""

import bpy

from .animation import CAUSTIC_OT_render_animation
from .bake import CAUSTIC_OT_bake, CAUSTIC_OT_unbake
from .bake_animation import CAUSTIC_OT_bake_animation
from .compare import CAUSTIC_OT_compare_cycles
from .dispersion import CAUSTIC_OT_toggle_dispersion
from .live import CAUSTIC_OT_toggle_live
from .paper_scene import CAUSTIC_OT_add_paper_scene
from .presets import CAUSTIC_OT_apply_preset
from .render import CAUSTIC_OT_render
from .render_with_caustics import CAUSTIC_OT_render_animation_with_caustics, CAUSTIC_OT_render_image_with_caustics

from . import bake_on_render, shortcuts
from ..jobs import kernels
from .engine_run import kernel_folder, shipped_kernels

_register_classes, _unregister_classes = bpy.utils.register_classes_factory((
    CAUSTIC_OT_render,
    CAUSTIC_OT_render_animation,
    CAUSTIC_OT_bake,
    CAUSTIC_OT_bake_animation,
    CAUSTIC_OT_unbake,
    CAUSTIC_OT_compare_cycles,
    CAUSTIC_OT_render_image_with_caustics,
    CAUSTIC_OT_render_animation_with_caustics,
    CAUSTIC_OT_apply_preset,
    CAUSTIC_OT_add_paper_scene,
    CAUSTIC_OT_toggle_dispersion,
    CAUSTIC_OT_toggle_live,
))


def register() -> None:
    _register_classes()
    bake_on_render.register()
    shortcuts.register()
    kernels.start(kernel_folder(), shipped_kernels())


def unregister() -> None:
    kernels.wait()
    shortcuts.unregister()
    bake_on_render.unregister()
    _unregister_classes()
