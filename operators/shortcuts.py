"""F12 and Ctrl-F12 with caustics. Blender runs an interface render's
handlers on its render thread, where the add-on must not write the
receivers' images, so with Live or Bake While Rendering on these keys go to
Render Image with Caustics and Render Animation with Caustics, which bake on
the main thread first. Otherwise they pass the key on to Blender's own
Render: an add-on's key map items come before Blender's (wm_keymap_addon_add
puts them at the head of the Screen key map)."""

import bpy

# (operator, key modifiers) of the Screen key map's F12 items taken over.
KEYS = (("caustic.render_image_with_caustics", {}),
        ("caustic.render_animation_with_caustics", {"ctrl": True}))

_items: list = []


def register() -> None:
    config = bpy.context.window_manager.keyconfigs.addon
    if config is None:
        return
    keymap = config.keymaps.new("Screen", space_type='EMPTY')
    for idname, modifiers in KEYS:
        item = keymap.keymap_items.new(idname, 'F12', 'PRESS', **modifiers)
        item.properties.from_shortcut = True
        _items.append((keymap, item))


def unregister() -> None:
    for keymap, item in _items:
        keymap.keymap_items.remove(item)
    _items.clear()
