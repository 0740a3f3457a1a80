"""What finding and ordering touching surfaces costs (tracing/contact.py;
issue 17, item 7).

    .venv/bin/python benchmarks/contact.py [--repeats 3]

Three scenes at 320x240 with the default settings (40,000 lamp rays as
beams, 4 samples per pixel): the paper's flat glass 1 mm above its floor
(no two objects' boxes meet: nothing is probed), the ball lens floating
inside a bowl (the boxes overlap, so every face of the glass is probed, and
nothing touches), and the paper's flat glass standing on its floor (its
base touches the floor: rays there are cast again against the two). For
each: the contact search's time and probe rays, then the whole render's
time and rays with the contacts as found and with none (the engine has no
switch: this script patches `Contacts` to find nothing). Each time is the
fastest of `repeats`. Writes benchmarks/results/contact.json and prints the
markdown table README quotes.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from datetime import date
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from caustic_addon import Dielectric, Diffuse, Object, RenderSettings, Scene, paper, render, shapes  # noqa: E402
from caustic_addon.tracing import accelerator, contact  # noqa: E402
from caustic_addon.tracing.accelerator import Accelerator  # noqa: E402
from speed import machine  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
PIXELS = (320, 240)


class _NoContacts:
    """Contacts that finds nothing: what the engine did before contact.py."""

    def __init__(self, accel):
        self.boxes, self.partners = {}, {}


def scenes() -> dict[str, Scene]:
    lifted = paper.scene("flat", pixels=PIXELS)
    standing = paper.scene("flat", height=-paper.GAP, pixels=PIXELS)
    in_bowl = Scene(objects=[Object("Bowl", shapes.bowl(1.5, 0.05), Diffuse(0.8)),
                             Object("Glass", shapes.uv_sphere(0.5, (0.0, 0.0, 1.0), 128, 64), Dielectric(1.5))],
                    lights=lifted.lights, camera=lifted.camera)
    return {"flat glass 1 mm above the floor": lifted, "ball lens floating in a bowl": in_bowl,
            "flat glass standing on the floor": standing}


def fastest(repeats: int, run) -> tuple[float, object]:
    best, value = float("inf"), None
    for _ in range(repeats):
        start = time.perf_counter()
        value = run()
        best = min(best, time.perf_counter() - start)
    return best, value


def measure(name: str, scene: Scene, repeats: int) -> dict:
    settings = RenderSettings()
    accel = Accelerator(scene.objects, scene.extent(), settings.threads)
    try:
        accel.rays_cast = 0
        search, found = fastest(repeats, lambda: contact.Contacts(accel))
        probes = accel.rays_cast // repeats
    finally:
        accel.close()
    on, with_contacts = fastest(repeats, lambda: render(scene, settings))
    original = accelerator.Contacts
    accelerator.Contacts = _NoContacts
    try:
        off, without = fastest(repeats, lambda: render(scene, settings))
    finally:
        accelerator.Contacts = original
    row = dict(scene=name, touching=len(found.boxes) > 0, search_seconds=search, probe_rays=probes,
               render_seconds=on, render_seconds_without=off,
               rays=with_contacts.stats["rays_lamp_pass"] + with_contacts.stats["rays_eye_pass"],
               rays_without=without.stats["rays_lamp_pass"] + without.stats["rays_eye_pass"])
    print(f"{name}: search {search * 1000:.1f} ms ({probes:,} probe rays), render {on:.2f} s / {off:.2f} s "
          f"without, rays {row['rays']:,} / {row['rays_without']:,}")
    return row


def markdown(rows: list[dict]) -> str:
    lines = ["| scene | objects touch | contact search | probe rays | render | render with no contacts |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {'yes' if r['touching'] else 'no'} | {r['search_seconds'] * 1000:.1f} ms "
                     f"| {r['probe_rays']:,} | {r['render_seconds']:.2f} s ({r['rays']:,} rays) "
                     f"| {r['render_seconds_without']:.2f} s ({r['rays_without']:,} rays) |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    rows = [measure(name, scene, args.repeats) for name, scene in scenes().items()]
    table = markdown(rows)
    RESULTS.mkdir(exist_ok=True)
    (RESULTS / "contact.json").write_text(json.dumps(
        dict(date=date.today().isoformat(), machine=machine(), repeats=args.repeats, pixels=PIXELS, rows=rows,
             table=table), indent=2) + "\n")
    print("\n" + table)


if __name__ == "__main__":
    main()
