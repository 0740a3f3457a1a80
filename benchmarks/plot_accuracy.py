"""One log-log plot of error against time on the ball-lens scene, for the
engine and, if measured, for Cycles.

    .venv/bin/python benchmarks/plot_accuracy.py

Reads benchmarks/results/accuracy.json (benchmarks/accuracy.py: the engine's
curves, points {lamp_rays, seconds, error}) and
benchmarks/results/cycles_accuracy.json if present
(benchmarks/cycles_accuracy.py: points {samples, seconds, error}), and
writes benchmarks/results/accuracy.png: relative L2 error (%) against wall
time (s), with the 10%, 5% and 2% levels.
"""

from __future__ import annotations

import json
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

RESULTS = Path(__file__).resolve().parent / "results"
THRESHOLDS = (0.10, 0.05, 0.02)


def load_curves() -> dict[str, tuple[list[dict], str]]:
    """Name -> (points, matplotlib line style): the engine's solid, Cycles' dashed."""
    curves = {name: (points, "o-") for name, points in
              json.loads((RESULTS / "accuracy.json").read_text())["curves"].items()}
    cycles = RESULTS / "cycles_accuracy.json"
    if cycles.exists():
        curves.update({name: (points, "s--") for name, points in json.loads(cycles.read_text())["curves"].items()})
    return curves


def plot(curves: dict[str, tuple[list[dict], str]], path: Path) -> None:
    """Error (%) against seconds of every curve, log-log, saved to `path` (PNG)."""
    fig, ax = plt.subplots(figsize=(8, 5.5))
    for name, (points, style) in curves.items():
        ax.loglog([p["seconds"] for p in points], [100 * p["error"] for p in points], style, label=name)
    for threshold in THRESHOLDS:
        ax.axhline(100 * threshold, color="grey", lw=0.6, ls=":")
        ax.annotate(f"{100 * threshold:g}%", (1, 100 * threshold), xycoords=("axes fraction", "data"),
                    xytext=(3, 0), textcoords="offset points", va="center", fontsize=8, color="grey")
    ax.set_xlabel("wall time (s)")
    ax.set_ylabel("relative L2 error of the caustic (%)")
    ax.set_title("Ball lens, 320x240: error against time")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)


def main() -> None:
    plot(load_curves(), RESULTS / "accuracy.png")
    print(RESULTS / "accuracy.png")


if __name__ == "__main__":
    main()
