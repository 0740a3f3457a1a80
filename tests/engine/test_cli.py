"""The command line without Blender: `python -m caustic_addon render`, its
scene file (config.py), its OBJ reader (obj.py) and its image files
(image_io.py)."""

import importlib.util
import io
import math
import os
import pty
import re
import select
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from caustic_addon import Reflector, RenderSettings, SceneError, paper, render, shapes
from caustic_addon.cli import config, obj
from caustic_addon.cli import main as cli
from caustic_addon.cli.image_io import read_exr, read_png, srgb_encode, write_image
from caustic_addon.cli.obj import ObjError, parse_obj, read_obj, write_obj

ROOT = Path(__file__).resolve().parents[2]
EXAMPLES = ROOT / "examples"

# A glass ball over a plane, small enough to render in well under a second.
SMALL = """\
[camera]
FOV = 40.0
pixx = 64
pixy = 48
eye = [0.0, -0.55, 0.4]
look_at = [0.0, 0.0, 0.03]

[plane]
size = 2.0

[lamp]
position = [0.0, 0.0, 0.6]
power = 0.8

[photons]
lamp_rays = 20000
energy = 10.0
map_scale = 5.0

[object]
ior = 1.5
position = [0.0, 0.0, 0.02]
scale = 0.1

[render]
spp = 1
"""


def run_cli(*args, cwd=ROOT):
    return subprocess.run([sys.executable, "-m", "caustic_addon", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def write(path: Path, text: str) -> Path:
    path.write_text(text, encoding="utf-8")
    return path


def assert_bad_input(proc, *fragments):
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    last = proc.stderr.strip().splitlines()[-1]
    assert last.startswith("error: ")
    for fragment in fragments:
        assert fragment in last


def luminance(rgba):
    return rgba[..., :3].astype(np.float64) @ [0.2126, 0.7152, 0.0722]


# --- whole renders -------------------------------------------------------------------------------------------


def test_help_lists_the_render_command():
    proc = run_cli("--help")
    assert proc.returncode == 0
    assert "render" in proc.stdout


def test_render_writes_a_png_with_a_caustic(tmp_path):
    scene = write(tmp_path / "scene.toml", SMALL)
    out = tmp_path / "new" / "folder" / "out.png"
    proc = run_cli("render", scene, EXAMPLES / "round.obj", "-o", out)
    assert proc.returncode == 0, proc.stderr
    # beams, the default: a 141 x 141 grid for 20,000 lamp rays, and what refinement adds
    traced, refined = (int(n.replace(",", "")) for n in
                       re.search(r"lamp rays ([\d,]+) \(([\d,]+) added by refinement\)", proc.stderr).groups())
    assert traced - refined == 141 ** 2
    image = read_png(out)
    assert image.shape == (48, 64, 4)
    assert (image[..., 3] == 255).all()
    lum = luminance(image)
    # the ball focuses the lamp into a spot far brighter than the lit plane
    assert lum.max() > 1.5 * np.median(lum)


def test_png_and_exr_of_one_render_agree_through_exposure(tmp_path):
    """The EXR holds the linear render; the PNG is its sRGB encoding, 2^EV
    brighter, to within the rounding of 8 bits (and of threads summing the
    illumination map in another order)."""
    scene = write(tmp_path / "scene.toml", SMALL)
    mesh = EXAMPLES / "round.obj"
    assert run_cli("render", scene, mesh, "-o", tmp_path / "out.exr").returncode == 0
    assert run_cli("render", scene, mesh, "-o", tmp_path / "out.png", "--exposure", "1").returncode == 0
    linear = read_exr(tmp_path / "out.exr")
    png = read_png(tmp_path / "out.png")
    assert linear[..., :3].max() > 1.0  # the caustic, kept unclipped
    expected = np.round(srgb_encode(2.0 * linear[..., :3]) * 255.0)
    assert np.abs(png[..., :3] - expected).max() <= 1


def test_command_line_overrides_the_scene_file(tmp_path):
    scene = write(tmp_path / "scene.toml", SMALL)
    proc = run_cli("render", scene, EXAMPLES / "round.obj", "-o", tmp_path / "out.png", "--lamp-rays", "0")
    assert proc.returncode == 0, proc.stderr
    assert "lamp rays 0," in proc.stderr


# --- bad input: error: <message>, status 2 -------------------------------------------------------------------


@pytest.mark.parametrize("edit, fragments", [
    (lambda t: t.replace("pixy = 48", "pixy = = 48"), ["scene.toml", "line 4"]),
    (lambda t: t.replace("size = 2.0", "size = 2.0\ncolour = 1.0"), ["plane.colour"]),
    (lambda t: t + "[lights]\npower = 1.0\n", ["[lights]"]),
    (lambda t: t.replace("lamp_rays = 20000", "lamp_rays = -5"), ["scene.toml: photons.lamp_rays", "integer >= 0", "-5"]),
    (lambda t: t.replace("lamp_rays = 20000", "lamp_rays = 2.5"), ["photons.lamp_rays"]),
    (lambda t: t.replace("lamp_rays = 20000", "count = 20000"), ["photons.count is now photons.lamp_rays"]),
    (lambda t: t.replace("pixx = 64", 'pixx = "64"'), ["camera.pixx"]),
    (lambda t: t.replace("eye = [0.0, -0.55, 0.4]\n", ""), ["camera.eye", "missing"]),
    (lambda t: t.replace("map_scale = 5.0", "map_scale = 0"), ["photons.map_scale"]),
    (lambda t: t.replace("power = 0.8", "power = 0.8\nstrength = 3.0"), ["lamp.strength", "point lamp"]),
    (lambda t: t.replace("ior = 1.5", "ior = nan"), ["object.ior"]),
    (lambda t: t.replace("map_scale = 5.0", 'density = "beam"\nbeam_refinement = 9'),
     ["photons.beam_refinement", "integer in 0..5"]),
    (lambda t: t.replace("ior = 1.5", 'ior = 1.5\nmaterial = "reflector"'), ["object.ior", "reflector object"]),
    (lambda t: t.replace("ior = 1.5", 'material = "metal"'), ["object.material", '"reflector"']),
    (lambda t: t.replace("ior = 1.5", "ior = 1.5\nabbe = 0"), ["object.abbe", "> 0", "inf for no dispersion"]),
    (lambda t: t.replace("ior = 1.5", "ior = 1.5\nabbe = nan"), ["object.abbe"]),
    (lambda t: t.replace("ior = 1.5", "ior = 1.5\nabsorption_color = [0.5, 0, 1]"), ["object.absorption_color",
                                                                                  "in (0, 1]"]),
    (lambda t: t.replace("ior = 1.5", "ior = 1.5\nabsorption_color = 0.5\nabsorption_distance = -1"),
     ["object.absorption_distance", "> 0"]),
    (lambda t: t.replace("ior = 1.5", "ior = 1.5\nabsorption_color = 0.5\nabsorption = 1.0"),
     ["object.absorption and object.absorption_color"]),
    (lambda t: t.replace("map_scale = 5.0", "map_scale = 5.0\nbands = 65"), ["photons.bands", "1..64"]),
    (lambda t: t.replace("ior = 1.5", "ior = 1.5\nroughness = 1.2"), ["object.roughness", "in 0..1"]),
], ids=["syntax", "unknown-key", "unknown-table", "negative-count", "fractional-count", "renamed-count", "string-pixx",
        "missing-eye", "zero-map-scale", "key-of-another-lamp", "nan-ior", "beam-refinement-too-deep",
        "ior-of-a-reflector", "unknown-material", "zero-abbe", "nan-abbe", "black-absorption-color",
        "negative-absorption-distance", "two-absorptions", "too-many-bands", "roughness-above-1"])
def test_bad_scene_file(tmp_path, edit, fragments):
    scene = write(tmp_path / "scene.toml", edit(SMALL))
    assert_bad_input(run_cli("render", scene, EXAMPLES / "round.obj", "-o", tmp_path / "out.png"), *fragments)


@pytest.mark.parametrize("obj_text, fragments", [
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\n", ["flat.obj", "no triangles"]),
    ("v 0 0 0\nv 1 0 0\n# a comment\nv 0 nan 0\nf 1 2 3\n", ["flat.obj", "line 4"]),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n", ["flat.obj", "line 4", "out of range"]),
], ids=["no-faces", "nan", "index-out-of-range"])
def test_bad_mesh_file(tmp_path, obj_text, fragments):
    scene = write(tmp_path / "scene.toml", SMALL)
    mesh = write(tmp_path / "flat.obj", obj_text)
    assert_bad_input(run_cli("render", scene, mesh, "-o", tmp_path / "out.png"), *fragments)


def test_missing_files_are_named(tmp_path):
    scene = write(tmp_path / "scene.toml", SMALL)
    assert_bad_input(run_cli("render", scene, tmp_path / "absent.obj", "-o", tmp_path / "out.png"), "absent.obj")
    assert_bad_input(run_cli("render", tmp_path / "absent.toml", EXAMPLES / "round.obj", "-o", tmp_path / "o.png"),
                     "absent.toml")


def test_bad_command_lines(tmp_path):
    scene = write(tmp_path / "scene.toml", SMALL)
    mesh = EXAMPLES / "round.obj"
    assert_bad_input(run_cli("render", scene, mesh, "-o", tmp_path / "out.jpg"), "out.jpg", ".jpg")
    assert not (tmp_path / "out.jpg").exists()
    assert_bad_input(run_cli("render", scene, mesh, "-o", tmp_path / "out.png", "--spp", "0"), "spp")
    assert_bad_input(run_cli("render", scene, mesh, "-o", tmp_path / "out.png", "--seed", "-1"), "--seed")
    assert_bad_input(run_cli("render", scene, mesh), "-o")
    assert_bad_input(run_cli("render", scene, mesh, "-o", scene / "out.png"), "scene.toml")  # a file as folder


def test_a_full_disk_leaves_no_half_image_and_the_earlier_one_whole(tmp_path, small_disk, fill_disk):
    """Issue 40: a new EXR was left half written, and a larger one written
    over a good one destroyed it."""
    scene = write(tmp_path / "scene.toml", SMALL)
    mesh = EXAMPLES / "round.obj"
    assert run_cli("render", scene, mesh, "-o", tmp_path / "good.exr").returncode == 0
    good = (tmp_path / "good.exr").read_bytes()
    disk = small_disk(8 * len(good))
    (disk / "out.exr").write_bytes(good)
    fill_disk(disk, 4096)
    for name, pixels in (("new.exr", "64"), ("out.exr", "128")):  # a new file, and a larger one over the good one
        larger = write(tmp_path / "larger.toml", SMALL.replace("pixx = 64", f"pixx = {pixels}"))
        proc = run_cli("render", larger, mesh, "-o", disk / name)
        assert_bad_input(proc, f"could not write '{disk / name}': No space left on device")
        assert sorted(p.name for p in disk.iterdir()) == ["filler", "out.exr"]
        assert (disk / "out.exr").read_bytes() == good


def test_an_exposure_past_float32_is_refused_for_exr_and_clips_in_png(tmp_path):
    scene = write(tmp_path / "scene.toml", SMALL)
    mesh = EXAMPLES / "round.obj"
    proc = run_cli("render", scene, mesh, "-o", tmp_path / "out.exr", "--exposure", "1000")
    assert_bad_input(proc, "an exposure of 1000 would make the brightest value 2^", "use an exposure of 12")
    assert not (tmp_path / "out.exr").exists()
    assert run_cli("render", scene, mesh, "-o", tmp_path / "out.png", "--exposure", "1000").returncode == 0
    image = read_png(tmp_path / "out.png")
    assert set(np.unique(image[..., :3])) <= {0, 255}


@pytest.mark.parametrize("edit, obj_text, fragment", [
    (("position = [0.0, 0.0, 0.02]", "position = [0.0, 0.0, 1e30]"), None, "'round' reaches 1e+30 m from the rest"),
    (None, "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1e30\nf 1 2 3\nf 1 2 4\nf 2 3 4\nf 3 1 4\n",
     "'spike' reaches 1e+29 m from the rest"),
    (("power = 0.8", "power = 1e300"), None, "its power of 1e+300 W (times its color) is past the 1e+30"),
], ids=["object position", "OBJ vertex", "lamp power"])
def test_huge_values_are_refused_by_name(tmp_path, edit, obj_text, fragment):
    """Each turned the whole image black, the lit plane included (issue 40)."""
    scene = write(tmp_path / "scene.toml", SMALL.replace(*edit) if edit else SMALL)
    mesh = write(tmp_path / "spike.obj", obj_text) if obj_text else EXAMPLES / "round.obj"
    assert_bad_input(run_cli("render", scene, mesh, "-o", tmp_path / "out.png"), fragment)
    assert not (tmp_path / "out.png").exists()


def test_ctrl_c_stops_cleanly_and_keeps_the_earlier_image(tmp_path):
    """Ctrl-C once the render runs (its progress bar drawn on a terminal):
    exit status 130, one line and no traceback, the earlier image whole."""
    scene = write(tmp_path / "scene.toml", SMALL.replace("lamp_rays = 20000", "lamp_rays = 4000000")
                  .replace("pixx = 64", "pixx = 320").replace("pixy = 48", "pixy = 240"))
    out = tmp_path / "out.exr"
    write_image(out, np.ones((2, 2, 4), dtype=np.float32))
    earlier = out.read_bytes()
    leader, follower = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "caustic_addon", "render", str(scene),
                             str(EXAMPLES / "round.obj"), "-o", str(out)], cwd=ROOT, stderr=follower)
    os.close(follower)
    seen, deadline = b"", time.monotonic() + 120
    while b"%" not in seen and time.monotonic() < deadline:
        if select.select([leader], [], [], 1.0)[0]:
            seen += os.read(leader, 4096)
    proc.send_signal(signal.SIGINT)
    status = proc.wait(timeout=120)
    while select.select([leader], [], [], 0.2)[0]:
        try:
            seen += os.read(leader, 4096)
        except OSError:
            break
    os.close(leader)
    text = seen.decode(errors="replace")
    assert status == 130, text
    assert "Traceback" not in text
    assert f"error: interrupted (Ctrl-C): nothing was written; '{out}' is as it was" in text
    assert out.read_bytes() == earlier
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.exr", "scene.toml"]


def test_engine_scene_errors_take_the_same_path(tmp_path, monkeypatch, capsys):
    def refuse(*args, **kwargs):
        raise SceneError("Glass: IOR must be a positive number (got 0)")

    monkeypatch.setattr(cli, "render", refuse)
    scene = write(tmp_path / "scene.toml", SMALL)
    status = cli.main(["render", str(scene), str(EXAMPLES / "round.obj"), "-o", str(tmp_path / "out.png")])
    assert status == 2
    assert capsys.readouterr().err.endswith("error: Glass: IOR must be a positive number (got 0)\n")


def test_progress_bar_draws_in_place_only_on_a_terminal():
    class Terminal(io.StringIO):
        def isatty(self):
            return True

    tty, pipe = Terminal(), io.StringIO()
    for stream in (tty, pipe):
        bar = cli.ProgressBar(stream)
        bar(0.25, "photon pass")
        bar(1.0, "eye pass")
        bar.close()
    assert pipe.getvalue() == ""
    frames = tty.getvalue().split("\r")[1:]
    assert len(frames) == 2 and "25%" in frames[0] and "100%" in frames[1] and frames[1].endswith("\n")
    assert frames[1].count("#") == cli.ProgressBar.WIDTH


# --- the scene file ------------------------------------------------------------------------------------------


def test_the_example_scene_is_the_papers():
    """examples/paper.toml with examples/round.obj is caustic_addon.paper's
    scene: the one the demo, the add-on and the benchmarks build."""
    cfg = config.load(EXAMPLES / "paper.toml")
    s = cfg.settings
    assert (s.lamp_rays, s.energy, s.density) == (paper.LAMP_RAYS, paper.ENERGY, RenderSettings().density)
    ours = cfg.scene(obj.read_obj(EXAMPLES / "round.obj"), "round")
    theirs = paper.scene("round", paper.INDICES["water"])
    for mine, expected in zip(ours.objects, theirs.objects):
        np.testing.assert_allclose(np.sort(mine.mesh.vertices, axis=0), np.sort(expected.mesh.vertices, axis=0),
                                   atol=1e-6)
        assert type(mine.material) is type(expected.material)
    assert ours.objects[1].material.ior == theirs.objects[1].material.ior
    np.testing.assert_allclose(ours.lights[0].position, theirs.lights[0].position)
    assert ours.lights[0].power == theirs.lights[0].power
    np.testing.assert_allclose(ours.camera.matrix, theirs.camera.matrix, atol=1e-12)
    assert (ours.camera.fov, ours.camera.pixx, ours.camera.pixy) == (theirs.camera.fov, *paper.PIXELS)


def test_scene_file_defaults_and_placement():
    text = SMALL.replace("map_scale = 5.0", 'map_scale = "auto"').replace("scale = 0.1", "scale = [0.1, 0.2, 0.3]")
    cfg = config.parse(text)
    # the density is the engine's default, as in the add-on
    assert cfg.settings.map_scale is None and cfg.settings.density == RenderSettings().density == "beam"
    assert cfg.settings.spp == 1 and cfg.settings.max_depth == 12
    mesh = shapes.cylinder(0.5, 0.5)
    scene = cfg.scene(mesh, "Cylinder")
    placed = scene.objects[1].mesh.vertices
    np.testing.assert_allclose(placed, mesh.vertices * [0.1, 0.2, 0.3] + [0.0, 0.0, 0.02])
    assert scene.objects[1].material.ior == 1.5
    assert scene.objects[1].material.abbe == math.inf and cfg.settings.bands == 6


def test_scene_file_dispersion_and_absorption_colour():
    text = SMALL.replace("ior = 1.5", "ior = 2.42\nabbe = 55\nabsorption_color = [0.9, 0.5, 0.25]\n"
                                      "absorption_distance = 0.02").replace("map_scale = 5.0", "map_scale = 5.0\nbands = 4")
    cfg = config.parse(text)
    assert cfg.material.abbe == 55.0 and cfg.settings.bands == 4
    np.testing.assert_allclose(np.exp(-cfg.material.absorption * 0.02), [0.9, 0.5, 0.25], rtol=1e-12)


def test_scene_file_roughness_of_glass_and_reflector():
    assert config.parse(SMALL.replace("ior = 1.5", "ior = 1.5\nroughness = 0.3")).material.roughness == 0.3
    reflector = config.parse(SMALL.replace("ior = 1.5", 'material = "reflector"\nroughness = 0.4')).material
    assert isinstance(reflector, Reflector) and reflector.roughness == 0.4
    assert config.parse(SMALL).material.roughness == 0.0


def test_a_reflector_in_the_scene_file_casts_a_caustic(tmp_path):
    """A mirror tube of reflectance 0.5 around the lamp's foot: its light
    lands on the plane (the mirror-tube physics is in test_reflectors.py)."""
    text = SMALL.replace("ior = 1.5", 'material = "reflector"\ncolor = [0.5, 0.5, 0.25]')
    cfg = config.parse(text)
    assert isinstance(cfg.material, Reflector)
    np.testing.assert_allclose(cfg.material.color, [0.5, 0.5, 0.25])
    mesh = tmp_path / "tube.obj"
    write_obj(mesh, shapes.tube(1.0, 0.5, segments=64))
    out = tmp_path / "tube.exr"
    done = run_cli("render", write(tmp_path / "scene.toml", text), mesh, "-o", out)
    assert done.returncode == 0, done.stderr
    result = render(cfg.scene(shapes.tube(1.0, 0.5, segments=64)), cfg.settings)
    red, green, blue = result.stats["flux_landed_w"]
    assert red > 0 and red == pytest.approx(green) and blue == pytest.approx(0.5 * red)
    assert np.isfinite(read_exr(out)).all()


def test_spot_and_sun_lamps():
    spot = SMALL.replace("power = 0.8", "power = 0.8\ntype = \"spot\"\ndirection = [0, 0, -2]\nspot_size = 30")
    lamp = config.parse(spot).lamp
    np.testing.assert_allclose(lamp.direction, [0, 0, -1])
    assert lamp.spot_size == pytest.approx(math.radians(30))
    sun = SMALL.replace("position = [0.0, 0.0, 0.6]\npower = 0.8",
                        'type = "sun"\ndirection = [0, 0, -1]\nstrength = 3.0')
    assert config.parse(sun).lamp.strength == 3.0
    with pytest.raises(config.ConfigError, match=r"lamp\.direction is missing"):
        config.parse(sun.replace("direction = [0, 0, -1]\n", ""))


def test_lamps_with_a_size():
    point = config.parse(SMALL.replace("power = 0.8", "power = 0.8\nradius = 0.05\nsoft_falloff = false")).lamp
    assert (point.radius, point.soft_falloff) == (0.05, False)
    sun = config.parse(SMALL.replace("position = [0.0, 0.0, 0.6]\npower = 0.8",
                                     'type = "sun"\ndirection = [0, 0, -1]\nstrength = 3.0\nangle = 10')).lamp
    assert sun.angle == pytest.approx(math.radians(10))
    area = config.parse(SMALL.replace("power = 0.8", 'power = 0.8\ntype = "area"\ndirection = [0, 0, -1]\n'
                                      'shape = "rectangle"\nsize = 0.4\nsize_y = 0.2\nspread = 90')).lamp
    # Blender's lamp frame: x cross y is the lamp's +Z, the way it does not face
    np.testing.assert_allclose([area.axis_x, area.axis_y], [[0.2, 0, 0], [0, 0.1, 0]], atol=1e-12)
    assert (area.shape, area.area, area.spread) == ("RECTANGLE", pytest.approx(0.08), pytest.approx(math.pi / 2))
    disk = config.parse(SMALL.replace("power = 0.8", 'power = 0.8\ntype = "area"\ndirection = [0, 1, 0]\n'
                                      'shape = "disk"\nsize = 0.4\nsize_y = 0.1')).lamp
    assert (disk.shape, disk.area) == ("ELLIPSE", pytest.approx(math.pi * 0.04))
    with pytest.raises(config.ConfigError, match=r"lamp\.up must not be parallel to lamp\.direction"):
        config.parse(SMALL.replace("power = 0.8", 'power = 0.8\ntype = "area"\ndirection = [0, 0, -1]\n'
                                   "up = [0, 0, 2]"))
    with pytest.raises(config.ConfigError, match=r"lamp\.soft_falloff must be true or false \(got 1\)"):
        config.parse(SMALL.replace("power = 0.8", "power = 0.8\nsoft_falloff = 1"))
    with pytest.raises(config.ConfigError, match=r"unknown key lamp\.angle \(the keys of a point lamp"):
        config.parse(SMALL.replace("power = 0.8", "power = 0.8\nangle = 1"))


def test_a_lamps_ray_visibility():
    """Blender's defaults: hidden from the camera, seen in reflections and through glass."""
    default = config.parse(SMALL).lamp.visibility
    assert (default.camera, default.glossy, default.transmission) == (False, True, True)
    seen = config.parse(SMALL.replace("power = 0.8", "power = 0.8\nvisible_camera = true\n"
                                      "visible_transmission = false")).lamp.visibility
    assert (seen.camera, seen.glossy, seen.transmission) == (True, True, False)


# --- OBJ -----------------------------------------------------------------------------------------------------

SQUARE = "v 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvn 0 0 3\n"


@pytest.mark.parametrize("face, has_uvs, has_normals", [
    ("f 1 2 3 4", False, False),
    ("f 1/1 2/2 3/3 4/4", True, False),
    ("f 1//1 2//1 3//1 4//1", False, True),
    ("f 1/1/1 2/2/1 3/3/1 4/4/1", True, True),
    ("f -4/-4/-1 -3/-3/-1 -2/-2/-1 -1/-1/-1", True, True),
    ("f 1/1/1 2/2 3//1 4", False, False),
])
def test_obj_face_formats(face, has_uvs, has_normals):
    mesh = parse_obj(SQUARE + face + "\n")
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2], [0, 2, 3]])
    assert (mesh.corner_uvs is not None) == has_uvs
    assert (mesh.corner_normals is not None) == has_normals
    if has_uvs:
        np.testing.assert_array_equal(mesh.corner_uvs, [[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]])
    if has_normals:
        np.testing.assert_array_equal(mesh.corner_normals, np.tile([0.0, 0.0, 1.0], (2, 3, 1)))


def test_obj_negative_indices_count_back_from_their_line():
    text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\nv 0 0 1\nf -4 -3 -1\nf 1 2 4\n"
    mesh = parse_obj(text)
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2], [0, 1, 3], [0, 1, 3]])


def test_obj_fans_polygons_and_ignores_what_is_not_geometry():
    angles = np.linspace(0, 2 * np.pi, 7)[:-1]
    hexagon = "".join(f"v {math.cos(a)} {math.sin(a)} 0 1.0\n" for a in angles)  # with the optional w
    text = ("# hexagon\nmtllib x.mtl\no Hex\ng group\ns 1\nusemtl glass\n" + hexagon
            + "vp 0.5\nl 1 2\nf 1 2 3 4 5 6 # the face\n")
    mesh = parse_obj(text)
    assert mesh.vertices.shape == (6, 3)
    np.testing.assert_array_equal(mesh.triangles, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]])
    corners = mesh.corners
    area = 0.5 * np.linalg.norm(np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1)
    assert area.sum() == pytest.approx(1.5 * math.sqrt(3))  # the regular hexagon's area


@pytest.mark.parametrize("text, message", [
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 -4\n", "line 4: vertex index -4 is out of range"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 0\n", "line 4: vertex index 0"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1 2/1 3/1\n", "line 4: texture coordinate index 1"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2\n", "line 5: a face needs at least 3 corners"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/x\n", "line 4: malformed face corner '3/x'"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3/1/1/1\n", "line 4: malformed face corner"),
    ("v 0 0\nf 1 1 1\n", "line 1: 'v' needs 3 numbers"),
    ("v 0 0 0\nv 1 0 zero\n", "line 2: malformed vertex"),
    ("v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nf 1//1 2//1 3//1\n", "line 4: the normal has zero length"),
    ("v 0 0 0\nv inf 0 0\nv 0 1 0\nf 1 2 3\n", "line 2: the vertex has NaN or infinite"),
])
def test_obj_errors_name_the_line(text, message):
    with pytest.raises(ObjError, match="^mesh.obj: " + re.escape(message)):
        parse_obj(text, "mesh.obj")


def test_obj_round_trip_keeps_corners_normals_and_uvs(tmp_path):
    for mesh in (shapes.uv_sphere(0.5, (0, 0, 0.5), 16, 8), shapes.plane(2.0)):
        write_obj(tmp_path / "m.obj", mesh, "a comment\nover two lines")
        back = read_obj(tmp_path / "m.obj")
        np.testing.assert_allclose(back.corners, mesh.corners, atol=1e-6)
        np.testing.assert_allclose(back.corner_normals, mesh.corner_normals, atol=2e-6)
        assert (back.corner_uvs is None) == (mesh.corner_uvs is None)
        if mesh.corner_uvs is not None:
            np.testing.assert_allclose(back.corner_uvs, mesh.corner_uvs, atol=1e-6)


def test_example_objects_are_the_papers_resting_at_the_origin():
    for name in paper.SHAPES:
        expected = paper.glass(name, -paper.GAP)
        path = EXAMPLES / f"{name}.obj"
        assert path.stat().st_size < 1_100_000
        mesh = read_obj(path)
        np.testing.assert_allclose(mesh.corners, expected.corners, atol=1e-6)
        np.testing.assert_allclose(mesh.corner_normals, expected.corner_normals, atol=2e-6)
        assert mesh.vertices[:, 2].min() == 0.0


# --- image files ---------------------------------------------------------------------------------------------


def test_srgb_encoding():
    np.testing.assert_allclose(srgb_encode(np.array([-1.0, 0.0, 0.0031308, 0.18, 1.0, 7.0, np.nan])),
                               [0.0, 0.0, 0.04045, 0.46135612950044164, 1.0, 1.0, 0.0], rtol=1e-4)


def test_exr_keeps_float32_exactly_and_png_quantises(tmp_path):
    rng = np.random.default_rng(3)
    image = (rng.random((5, 7, 4)) * 50.0).astype(np.float32)
    image[0, 0] = [1e-8, 65504.0, 3e5, 0.0]
    write_image(tmp_path / "a.exr", image)
    np.testing.assert_array_equal(read_exr(tmp_path / "a.exr"), image)
    write_image(tmp_path / "a.png", image / 50.0, exposure=-1.0)
    expected = np.round(srgb_encode(image[..., :3] / 100.0) * 255.0)
    np.testing.assert_array_equal(read_png(tmp_path / "a.png")[..., :3], expected)


@pytest.mark.skipif(importlib.util.find_spec("bpy") is None, reason="bpy is not installed")
def test_blender_reads_both_images_and_we_read_blender_s_zip_exr(tmp_path):
    """Blender's own readers agree with ours, pixel for pixel, and ours
    reads the ZIP, ZIPS and uncompressed EXR files Blender writes."""
    rng = np.random.default_rng(4)
    image = (rng.random((37, 9, 4)) * 20.0).astype(np.float32)
    image[5:30, 2:6] = 0.0  # runs of zeros, as renders have, which ZIP shrinks
    write_image(tmp_path / "b.exr", image)
    write_image(tmp_path / "b.png", image / 20.0)
    script = ("import sys, bpy, numpy as np\n"
              "for path in sys.argv[1:3]:\n"
              "    im = bpy.data.images.load(path)\n"
              "    w, h = im.size\n"
              "    px = np.array(im.pixels[:], dtype=np.float32).reshape(h, w, 4)[::-1]\n"
              "    np.save(path + '.npy', px)\n"
              "settings = bpy.context.scene.render.image_settings\n"
              "settings.file_format, settings.color_depth = 'OPEN_EXR', '32'\n"
              "im = bpy.data.images.new('x', 9, 37, alpha=True, float_buffer=True)\n"
              "im.colorspace_settings.name = 'Linear Rec.709'\n"
              "im.pixels.foreach_set(np.load(sys.argv[3]).ravel())\n"
              "for codec in ('ZIP', 'ZIPS', 'NONE'):\n"
              "    settings.exr_codec = codec\n"
              "    im.save_render(sys.argv[4] + codec + '.exr', scene=bpy.context.scene)\n")
    np.save(tmp_path / "rows.npy", image[::-1])
    proc = subprocess.run([sys.executable, "-c", script, str(tmp_path / "b.exr"), str(tmp_path / "b.png"),
                           str(tmp_path / "rows.npy"), str(tmp_path / "blender_")],
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    np.testing.assert_array_equal(np.load(tmp_path / "b.exr.npy"), image)
    np.testing.assert_allclose(np.load(tmp_path / "b.png.npy") * 255.0, read_png(tmp_path / "b.png"), atol=1e-3)
    for codec in ("ZIP", "ZIPS", "NONE"):
        np.testing.assert_array_equal(read_exr(tmp_path / f"blender_{codec}.exr"), image, err_msg=codec)


def test_a_render_that_must_compile_kernels_says_so_first(tmp_path):
    """Where a kernel is missing from the cache, the CLI says it compiles the
    kernels, once, and how long that took, before the render's progress and
    outside the render's time; with every kernel cached it says nothing."""
    from caustic_addon.util import jit
    cache = tmp_path / "cache"
    kernels = cache / jit._ENGINE_NAME / jit._DIGEST
    if jit.cache_folder().is_dir():
        shutil.copytree(jit.cache_folder(), kernels)
    for missing in sorted(kernels.rglob(f"*.py{sys.version_info.major}{sys.version_info.minor}.nbi"))[:1]:
        missing.unlink()
    scene = tmp_path / "small.toml"
    scene.write_text(SMALL)
    mesh = tmp_path / "ball.obj"
    write_obj(mesh, shapes.uv_sphere(1.0, segments=16, rings=8))
    script = ("import sys; from caustic_addon.util.jit import use_kernel_cache; use_kernel_cache(sys.argv[1]); "
              "from caustic_addon.cli.main import main; sys.exit(main(sys.argv[2:]))")
    for first in (True, False):
        run = subprocess.run([sys.executable, "-c", script, str(cache), "render", str(scene), str(mesh),
                              "-o", str(tmp_path / "out.png")], cwd=ROOT, capture_output=True, text=True)
        assert run.returncode == 0, run.stderr
        said = run.stderr
        if first:
            compiling, summary = said.index("compiling the engine's kernels, once"), said.index("out.png: 64x48")
            assert compiling < said.index("compiled in ") < summary
        else:
            assert "compiling the engine's kernels" not in said and "compiled in " not in said
