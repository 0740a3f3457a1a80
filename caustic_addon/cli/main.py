"""Render without Blender, from the paper's inputs:

    python -m caustic_addon render scene.toml object.obj -o out.png

scene.toml is described in config.py (and examples/paper.toml); the mesh is
a Wavefront OBJ file. The image is written as 8-bit sRGB PNG or float32
OpenEXR by its extension. Progress goes to stderr, as a bar redrawn in place
on a terminal, then one summary line and any warnings. Bad input, and an
image that cannot be written whole (written to a temporary file, checked
and renamed: files.py), prints `error: <message>` on stderr and exits with
status 2. Ctrl-C stops the render between chunks (a second stops it at
once), writes nothing, and exits with status 130, as a shell reports a
program that SIGINT ended; an earlier image at the output's path is left as
it was.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import signal
import sys
import threading
import time
from pathlib import Path
from typing import Optional, TextIO

from ..errors import Cancelled, SceneError
from ..renderer import render
from ..util.jit import compile_kernels, kernels_cached
from . import config, files, image_io, obj

EXIT_BAD_INPUT = 2
EXIT_INTERRUPTED = 128 + signal.SIGINT

# Exceptions whose message tells the user what to fix; anything else is a bug.
_BAD_INPUT = (config.ConfigError, obj.ObjError, image_io.ImageFormatError, SceneError)


class _Parser(argparse.ArgumentParser):
    """argparse that reports bad arguments as `error: ...` like every other bad input."""

    def error(self, message):
        self.print_usage(sys.stderr)
        self.exit(EXIT_BAD_INPUT, f"error: {message}\n")


def _exposure(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not math.isfinite(value):
        raise argparse.ArgumentTypeError(f"must be a finite number of stops (got {text!r})")
    return value


def _seed(text: str) -> int:
    if not text.isdigit():
        raise argparse.ArgumentTypeError(f"must be an integer >= 0 (got {text!r})")
    return int(text)


def build_parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="python -m caustic_addon",
                     description="Render caustics through a transparent mesh or off a mirror, without Blender.")
    commands = parser.add_subparsers(dest="command", required=True, parser_class=_Parser)
    cmd = commands.add_parser("render", help="render a scene file and a mesh to an image",
                              description="Render the scene file CONFIG (TOML; see examples/paper.toml) with "
                                          "the mesh MESH (Wavefront OBJ; glass or a reflector, as object.material says) to OUT.")
    cmd.add_argument("config", metavar="CONFIG", help="scene file, TOML")
    cmd.add_argument("mesh", metavar="MESH", help="the caster, Wavefront OBJ")
    cmd.add_argument("-o", "--output", metavar="OUT", required=True,
                     help="image to write: .png (8-bit sRGB) or .exr (float32 linear); its folder is created")
    cmd.add_argument("--lamp-rays", metavar="N", type=int, help="lamp rays, overriding photons.lamp_rays")
    cmd.add_argument("--spp", metavar="N", type=int, help="eye samples per pixel, overriding render.spp")
    cmd.add_argument("--exposure", metavar="EV", type=_exposure, default=0.0,
                     help="scale the image by 2^EV before writing (default 0)")
    cmd.add_argument("--seed", metavar="N", type=_seed, help="random seed, overriding render.seed")
    return parser


class ProgressBar:
    """A text bar redrawn in place with \\r when `stream` is a terminal; silent otherwise."""

    WIDTH = 30

    def __init__(self, stream: TextIO):
        self.stream = stream
        self.live = stream.isatty()
        self.drawn = False

    def __call__(self, fraction: float, stage: str) -> None:
        if not self.live:
            return
        filled = round(fraction * self.WIDTH)
        self.stream.write(f"\r[{'#' * filled}{'.' * (self.WIDTH - filled)}] {fraction:4.0%} {stage:<12}")
        self.stream.flush()
        self.drawn = True

    def close(self) -> None:
        if self.drawn:
            self.stream.write("\n")


class Interrupt:
    """Ctrl-C while a render runs: the first asks it to stop between chunks
    (the render's `cancel`), a second stops it at once (KeyboardInterrupt).
    A context manager; Python's own handling is put back on leaving, and
    left alone off the main thread, where no signal handler can be set."""

    def __init__(self):
        self.asked = False
        self._previous = None

    def __call__(self) -> bool:
        return self.asked

    def _handle(self, signum, frame) -> None:
        if self.asked:
            raise KeyboardInterrupt
        self.asked = True

    def __enter__(self) -> "Interrupt":
        if threading.current_thread() is threading.main_thread():
            self._previous = signal.signal(signal.SIGINT, self._handle)
        return self

    def __exit__(self, *exc) -> None:
        if self._previous is not None:
            signal.signal(signal.SIGINT, self._previous)


def run_render(args: argparse.Namespace, err: TextIO) -> None:
    """The `render` command; raises one of _BAD_INPUT for bad input."""
    image_io.check_format(args.output)
    cfg = config.load(args.config)
    overrides = {name: value for name, value in
                 (("lamp_rays", args.lamp_rays), ("spp", args.spp), ("seed", args.seed)) if value is not None}
    settings = dataclasses.replace(cfg.settings, **overrides)
    try:
        settings.validate()
    except ValueError as exc:  # the scene file's values are checked already: an option is out of range
        raise config.ConfigError(f"command line: {exc}") from None
    mesh = obj.read_obj(args.mesh)
    scene = cfg.scene(mesh, Path(args.mesh).stem)

    if not kernels_cached():
        err.write("compiling the engine's kernels, once (about half a minute)\n")
        clock = time.perf_counter()
        compile_kernels()
        err.write(f"compiled in {time.perf_counter() - clock:.1f} s\n")
    clock = time.perf_counter()
    bar = ProgressBar(err)
    try:
        with Interrupt() as interrupt:
            result = render(scene, settings, progress=bar, cancel=interrupt)
    finally:
        bar.close()
    seconds = time.perf_counter() - clock

    output = Path(args.output)
    output.parent.mkdir(parents=True, exist_ok=True)
    image_io.write_image(output, result.image, args.exposure)

    stats, stage = result.stats, result.stats["seconds"]
    refined = f" ({stats['lamp_rays_refined']:,} added by refinement)" if stats["lamp_rays_refined"] else ""
    err.write(f"{output}: {scene.camera.pixx}x{scene.camera.pixy} in {seconds:.2f} s "
              f"(bvh {stage['bvh']:.2f} s, lamp pass {stage['lamp_pass']:.2f} s, eye {stage['eye']:.2f} s); "
              f"lamp rays {stats['lamp_rays']:,}{refined}, landed {stats['landed']:,}\n")
    for warning in result.warnings:
        err.write(f"warning: {warning}\n")


def main(argv: Optional[list[str]] = None) -> int:
    """Run the command line `argv` (default: sys.argv[1:]); return the exit status."""
    args = build_parser().parse_args(argv)
    try:
        run_render(args, sys.stderr)
    except _BAD_INPUT as exc:
        return _fail(str(exc))
    except files.WriteError as exc:
        return _fail(str(exc))
    except OSError as exc:  # reading errors are among _BAD_INPUT: this is the image's folder
        return _fail(f"cannot write {args.output}: {exc.filename or args.output}: {exc.strerror or exc}")
    except (Cancelled, KeyboardInterrupt):
        earlier = f"; '{args.output}' is as it was" if Path(args.output).exists() else ""
        return _fail(f"interrupted (Ctrl-C): nothing was written{earlier}", EXIT_INTERRUPTED)
    return 0


def _fail(message: str, status: int = EXIT_BAD_INPUT) -> int:
    sys.stderr.write(f"error: {message}\n")
    return status
