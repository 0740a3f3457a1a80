"""The `blender` command of the test farm's Workers: the real bpy module of
the Blender under test, the add-on registered from the source tree, and
Blender's command line as far as the job type (examples/flamenco/caustics.js)
and Flamenco use it, in Blender's order. Any other argument is refused by
name, with exit status 1.

    python farm_blender.py -b -y FILE [--python-exit-code N] [--python-expr EXPR]
                           [--render-output PATH] [--render-format FORMAT]
                           [--render-frame 1,3,5..6] [-- ARGS...]

As Blender: `--python-expr` sees the whole command line in sys.argv, an
exception in it is printed and Blender goes on unless `--python-exit-code`
was given; each frame `--render-frame` renders is written by the output
path's rules and reported with Blender's "Saved:" and "Time:" lines, which
Flamenco counts.
"""

import sys
import time
import traceback
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

FLAGS = ("-b", "--background", "-y", "--enable-autoexec")
VALUED = ("--python-exit-code", "--python-expr", "--render-output", "--render-format", "--render-frame")


def frames_of(spec: str) -> list[int]:
    """Blender's frame list: '1,3,5..6'."""
    frames = []
    for part in spec.split(","):
        first, _, last = part.partition("..")
        frames += range(int(first), int(last or first) + 1)
    return frames


def render_frames(bpy, spec: str) -> None:
    scene = bpy.context.scene
    for frame in frames_of(spec):
        start = time.perf_counter()
        scene.frame_start = scene.frame_end = frame
        bpy.ops.render.render(animation=True)
        if bpy.app.version >= (5, 0, 0):
            # Blender 5's bpy module logs these lines through a logger it does not print; 4.x's prints them
            seconds = time.perf_counter() - start
            print(f"Saved: '{bpy.path.abspath(scene.render.frame_path(frame=frame))}'")
            print(f"Time: {int(seconds // 60):02d}:{seconds % 60:05.2f} (Saving: 00:00.00)", flush=True)


def main(argv: list[str]) -> int:
    own = argv[:argv.index("--")] if "--" in argv else argv
    for i, arg in enumerate(own):
        valued = i > 0 and own[i - 1] in VALUED
        if arg.startswith("-") and not valued and arg not in FLAGS + VALUED:
            print(f"blender: unknown argument '{arg}'", file=sys.stderr)
            return 1
    import bpy
    import conftest

    addon = conftest.load_addon()
    addon.register()
    sys.argv = ["blender", *argv]
    exit_code = 0
    try:
        i = 0
        while i < len(own):
            arg, value = own[i], own[i + 1] if i + 1 < len(own) else None
            i += 2 if arg in VALUED else 1
            if arg in FLAGS:
                continue
            if arg == "--python-exit-code":
                exit_code = int(value)
            elif arg == "--python-expr":
                try:
                    exec(compile(value, "<string>", "exec"), {"__name__": "__main__"})
                except Exception:
                    traceback.print_exc()
                    if exit_code:
                        return exit_code
            elif arg == "--render-output":
                bpy.context.scene.render.filepath = value
            elif arg == "--render-format":
                bpy.context.scene.render.image_settings.file_format = value
            elif arg == "--render-frame":
                render_frames(bpy, value)
            else:
                bpy.ops.wm.open_mainfile(filepath=arg)
        return 0
    finally:
        sys.stdout.flush()
        addon.unregister()  # Blender 4.2's bpy module crashes at exit while an operator is registered


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
