"""Mitsuba 3's particle tracer on a scene the engine exported: the unbiased
reference of benchmarks/mitsuba_folds.py. Runs in Mitsuba's own venv (never
the add-on's), LLVM variant:

    DRJIT_LIBLLVM_PATH=/usr/lib/x86_64-linux-gnu/libLLVM-19.so \\
        /tmp/mitsuba-venv/bin/python benchmarks/references/mitsuba_ptracer.py scene.npz out.npz --spp 64 --passes 16

The scene file (mitsuba_folds.export_scene) holds a JSON description under
"meta" (camera, lamp, max_depth; each shape's material) and each shape's
unshared triangle corners and shading normals. Every pass renders `spp`
particles per pixel with a seed of its own; the output holds each pass's
image (passes, h, w) (the red channel: the scenes are white) and its wall
and CPU seconds.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import tempfile
import time

import numpy as np

os.environ.setdefault("DRJIT_LIBLLVM_PATH", "/usr/lib/x86_64-linux-gnu/libLLVM-19.so")
import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402

mi.set_variant("llvm_ad_rgb")


def cpu_seconds() -> float:
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def write_ply(path: str, corners: np.ndarray, normals: np.ndarray) -> None:
    """A binary PLY of unshared triangles `corners (t,3,3)` with shading
    normals `normals (t,3,3)` per corner."""
    t = len(corners)
    vertex = np.concatenate([corners.reshape(-1, 3), normals.reshape(-1, 3)], axis=1).astype("<f4")
    faces = np.empty(t, dtype=[("n", "u1"), ("v", "<i4", 3)])
    faces["n"] = 3
    faces["v"] = np.arange(3 * t).reshape(t, 3)
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {3 * t}\n"
              "property float x\nproperty float y\nproperty float z\n"
              "property float nx\nproperty float ny\nproperty float nz\n"
              f"element face {t}\nproperty list uchar int vertex_indices\nend_header\n")
    with open(path, "wb") as f:
        f.write(header.encode("ascii"))
        f.write(vertex.tobytes())
        f.write(faces.tobytes())


def scene_dict(meta: dict, data, folder: str) -> dict:
    cam = meta["camera"]
    out = {
        "type": "scene",
        "integrator": {"type": "ptracer", "max_depth": meta["max_depth"], "hide_emitters": True},
        "sensor": {
            "type": "perspective", "fov": cam["fov_deg"], "fov_axis": cam["fov_axis"],
            "near_clip": 1e-3, "far_clip": 1e4,
            "to_world": mi.ScalarTransform4f().look_at(origin=cam["eye"], target=cam["target"], up=cam["up"]),
            "film": {"type": "hdrfilm", "width": cam["pixx"], "height": cam["pixy"], "pixel_format": "rgb",
                     "rfilter": {"type": "box"}, "sample_border": False},
            "sampler": {"type": "independent", "sample_count": 1},
        },
    }
    lamp = meta["lamp"]
    if lamp["type"] == "spot":
        out["lamp"] = {"type": "spot", "intensity": {"type": "rgb", "value": [lamp["intensity"]] * 3},
                       "cutoff_angle": lamp["cutoff_deg"], "beam_width": lamp["beam_width_deg"],
                       "to_world": mi.ScalarTransform4f().look_at(origin=lamp["position"], target=lamp["target"],
                                                                  up=lamp["up"])}
    else:
        out["lamp"] = {"type": "directional", "direction": lamp["direction"],
                       "irradiance": {"type": "rgb", "value": [lamp["irradiance"]] * 3}}
    for k, shape in enumerate(meta["shapes"]):
        path = os.path.join(folder, f"shape{k}.ply")
        write_ply(path, data[f"corners{k}"], data[f"normals{k}"])
        if shape["bsdf"] == "dielectric":
            bsdf = {"type": "dielectric", "int_ior": shape["ior"], "ext_ior": 1.0}
        else:
            bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [shape["albedo"]] * 3}}
        out[f"shape{k}"] = {"type": "ply", "filename": path, "bsdf": bsdf}
    return out


def main() -> None:
    parser = argparse.ArgumentParser()
    parser.add_argument("scene")
    parser.add_argument("out")
    parser.add_argument("--spp", type=int, default=64)
    parser.add_argument("--passes", type=int, default=1)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=2)
    args = parser.parse_args()
    dr.set_thread_count(args.threads)
    data = np.load(args.scene)
    meta = json.loads(str(data["meta"]))
    with tempfile.TemporaryDirectory() as folder:
        scene = mi.load_dict(scene_dict(meta, data, folder))
    images, walls, cpus = [], [], []
    for p in range(args.passes):
        wall, cpu = time.perf_counter(), cpu_seconds()
        image = np.array(mi.render(scene, spp=args.spp, seed=args.seed + p))
        walls.append(time.perf_counter() - wall)
        cpus.append(cpu_seconds() - cpu)
        images.append(image[..., 0].astype(np.float64))
        print(f"pass {p}: {walls[-1]:.1f} s (CPU {cpus[-1]:.1f} s)", flush=True)
    np.savez(args.out, images=np.array(images), wall=np.array(walls), cpu=np.array(cpus), spp=args.spp)


if __name__ == "__main__":
    main()
