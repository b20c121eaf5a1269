#!/usr/bin/env python3
"""Time to quality: Photonix against Mitsuba 3 at equal error on the shared Cornell scenes.

For each scene (default: cornell-box and cornell-caustics) this
  1. renders with Photonix under each time budget on each backend (`--backend gpu`: the Vulkan
     kernels, lavapipe on a machine without a GPU; `--backend cpu`: the CPU twin), timing the
     whole command (process start, scene preparation, device set-up, photons, passes, writing);
  2. renders the same scene with Mitsuba 3's path tracer at several sample counts (the scene built
     from ../shared/reference/<scene>/scene.json, the way the references were made: integrator
     `path`, max_depth 65, Russian roulette from depth 5, box filter), timing mi.render after a
     warm-up render that compiles its kernels;
  3. measures every image's relMSE against ../shared/reference/<scene>/reference.exr
     (mean over pixels and channels of (t - r)^2 / (r^2 + 0.01), as `photonix diff` prints it);
  4. measures the reference's own noise, the floor under every renderer's error against it: two
     more Mitsuba renders with other seeds (`--floor-spp`, 1024 by default) give
     floor = mean of (m1 - r)(m2 - r) / (r^2 + 0.01), whose expectation is the reference's
     variance in relMSE's units (the two renders' noise is independent of each other and of the
     reference's, and Mitsuba is unbiased);
  5. fits Mitsuba's error as k / spp + floor and its time as t0 + c * spp (least squares), and prints for
     each Photonix render the time Mitsuba needs for the same error divided by Photonix's time
     (the equal-error time ratio; above 1 means Photonix is faster), and the same ratio of CPU
     time (user + system of all threads: Mitsuba's process time around mi.render, Photonix's
     child-process usage), which other processes on a shared machine disturb far less than the
     wall clock (both renderers use the same 2 cores; lavapipe's threads count as Photonix's).
     Equal error against the reference is then equal error against the truth: Mitsuba needs
     k / (relMSE - floor) samples. The last column gives the ratio without the floor (k / relMSE,
     the method of the figures before 2026-12-02), which favours Mitsuba wherever the reference
     is noisy.

Needs: a release build (`cargo build --release`), `pip install mitsuba` (3.9 was used), and for
the fast variant Debian's `libllvm19` (the script sets DRJIT_LIBLLVM_PATH=libLLVM-19.so unless it
is set); without LLVM it falls back to `scalar_rgb`. `ci/setup --bench` installs both (Mitsuba into
target/bench-tools: run this script with target/bench-tools/bin/python). On a lent GPU machine,
benches/device/ packs and runs it against Mitsuba's CUDA variant. Slow by design (minutes): never
run in CI.

    python3 benches/time_to_quality.py                     # 30 s budgets, both backends
    python3 benches/time_to_quality.py --budgets 10,30 --backends cpu --scenes cornell-box
"""

import argparse
import json
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
REFERENCES = REPO.parent / "shared" / "reference"


# ---------------------------------------------------------------------------------------------
# Error metric


def read_exr(path):
    import numpy as np
    import mitsuba as mi

    return np.array(mi.Bitmap(str(path)).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32), dtype=np.float64)


def rel_mse(test, ref):
    """mean over pixels and channels of (t - r)^2 / (r^2 + 0.01), as src/io/metrics.rs."""
    return float((((test - ref) ** 2) / (ref**2 + 0.01)).mean())


def mean_ratio(test, ref):
    """Per-channel ratio of mean radiance: the energy check (1 = unbiased on average)."""
    return [float(test[..., c].mean() / ref[..., c].mean()) for c in range(3)]


# ---------------------------------------------------------------------------------------------
# Mitsuba 3: the scene from the renderer-agnostic scene.json


def choose_variant(requested):
    import mitsuba as mi

    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "libLLVM-19.so")
    for variant in [requested] if requested else ["llvm_ad_rgb", "scalar_rgb"]:
        try:
            mi.set_variant(variant)
            return variant
        except Exception as e:  # noqa: BLE001 (drjit raises several kinds when LLVM is missing)
            print(f"mitsuba variant {variant} unavailable: {e}", file=sys.stderr)
    sys.exit("no usable Mitsuba variant; pip install mitsuba (and apt-get install libllvm19)")


def write_quad_obj(path, vertices, uv=None):
    """A quad as the two triangles (v0, v1, v2) and (v0, v2, v3), as scene.json asks, with its
    per-vertex uv where it has them (Mitsuba's OBJ loader flips v and its textures put row 0 at
    the top: the two flips cancel, as scene.json's texture notes say)."""
    with open(path, "w") as f:
        for v in vertices:
            f.write("v {} {} {}\n".format(*v))
        if uv is None:
            f.write("f 1 2 3\nf 1 3 4\n")
        else:
            for t in uv:
                f.write("vt {} {}\n".format(*t))
            f.write("f 1/1 2/2 3/3\nf 1/1 3/3 4/4\n")


def rgb(value):
    return {"type": "rgb", "value": value}


def mitsuba_scene(scene_json, mesh_dir, max_depth):
    """The scene of a shared reference as Mitsuba 3 rendered it: path tracer, or the volumetric
    path tracer where the scene has media; diffuse, mirror, dielectric, GGX rough conductor and
    dielectric, checkerboard and bitmap textures, null medium boundaries."""
    import mitsuba as mi

    root = Path(scene_json).parent
    s = json.loads(Path(scene_json).read_text())

    def texture(value):
        if isinstance(value, dict) and "texture" in value:
            t = s["textures"][value["texture"]]
            if t["type"] == "checkerboard":
                scale = t.get("uv_scale", 1)
                return {"type": "checkerboard", "color0": rgb(t["color0"]), "color1": rgb(t["color1"]),
                        "to_uv": mi.ScalarTransform4f.scale([scale, scale, 1])}
            if t["type"] == "bitmap":
                return {"type": "bitmap", "filename": str(root / t["file"]), "raw": False, "filter_type": "bilinear"}
            raise SystemExit(f"{scene_json}: texture type {t['type']} is not translated to Mitsuba")
        return rgb(value)

    def bsdf(name):
        m = s["materials"][name]
        if m["type"] == "diffuse":
            # Diffuse surfaces reflect alike on both sides; Mitsuba's BSDFs are one-sided.
            return {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": texture(m["reflectance"])}}
        if m["type"] == "dielectric":
            return {"type": "dielectric", "int_ior": m["ior"], "ext_ior": m.get("outside_ior", 1.0)}
        if m["type"] == "mirror":
            return {"type": "conductor", "material": "none", "specular_reflectance": rgb(m["reflectance"])}
        if m["type"] == "rough_conductor":
            return {"type": "roughconductor", "distribution": m["distribution"], "alpha": m["alpha"],
                    "eta": rgb(m["eta"]), "k": rgb(m["k"])}
        if m["type"] == "rough_dielectric":
            return {"type": "roughdielectric", "distribution": m["distribution"], "alpha": m["alpha"],
                    "int_ior": m["ior"], "ext_ior": m.get("outside_ior", 1.0)}
        if m["type"] == "null":
            return {"type": "null"}
        raise SystemExit(f"{scene_json}: material type {m['type']} is not translated to Mitsuba")

    def medium(name):
        m = s["media"][name]
        if m["type"] != "homogeneous" or m["phase"]["type"] != "isotropic":
            raise SystemExit(f"{scene_json}: medium {name} is not translated to Mitsuba")
        # sigma_t per mm given directly (the scene is in mm), as scene.json's "mitsuba" note does.
        return {"type": "homogeneous", "sigma_t": rgb(m["sigma_t_per_mm"]), "albedo": rgb(m["albedo"]),
                "phase": {"type": "isotropic"}}

    cam = s["camera"]
    integrator = "volpath" if s.get("media") else "path"
    d = {
        "type": "scene",
        "integrator": {"type": integrator, "max_depth": max_depth, "rr_depth": 5},
        "sensor": {
            "type": "perspective",
            "fov": cam["fov_deg"],
            "fov_axis": "x",
            "to_world": mi.ScalarTransform4f.look_at(origin=cam["position"], target=cam["look_at"], up=cam["up"]),
            "film": {
                "type": "hdrfilm",
                "width": s["image"]["width"],
                "height": s["image"]["height"],
                "rfilter": {"type": "box"},
                "pixel_format": "rgb",
            },
            "sampler": {"type": "independent", "sample_count": 1},
        },
    }
    emitters = {l["shape"]: l for l in s["lights"]}
    for i, shape in enumerate(s["shapes"]):
        key = f"shape_{i}_{shape.get('name', shape['type'])}"
        if shape["type"] == "quad":
            obj = Path(mesh_dir) / f"{key}.obj"
            write_quad_obj(obj, shape["vertices"], shape.get("uv"))
            entry = {"type": "obj", "filename": str(obj), "face_normals": True}
        elif shape["type"] == "sphere":
            entry = {"type": "sphere", "center": shape["center"], "radius": shape["radius"]}
        elif shape["type"] == "box" and "mesh_file" in shape:
            entry = {"type": "obj", "filename": str(root / shape["mesh_file"]), "face_normals": True}
        else:
            raise SystemExit(f"{scene_json}: shape type {shape['type']} is not translated to Mitsuba")
        entry["bsdf"] = bsdf(shape["material"])
        if "interior_medium" in shape:
            entry["interior"] = medium(shape["interior_medium"])
        light = emitters.get(shape.get("name"))
        if light is not None:
            # One-sided Lambertian emitter on the side of the winding normal (downwards).
            entry["emitter"] = {"type": "area", "radiance": rgb(light["radiance"])}
        d[key] = entry
    return mi.load_dict(d)


def run_mitsuba(scene_name, spps, variant, reference, max_depth, floor_spp):
    import numpy as np
    import mitsuba as mi

    rows = []
    floor = None
    with tempfile.TemporaryDirectory() as tmp:
        scene = mitsuba_scene(REFERENCES / scene_name / "scene.json", tmp, max_depth)
        # Warm-up: compiles the path tracer's kernels (cached afterwards), untimed.
        np.array(mi.render(scene, spp=1, seed=999))
        for spp in spps:
            t = time.perf_counter()
            c = time.process_time()
            image = np.array(mi.render(scene, spp=spp, seed=spp), dtype=np.float64)
            seconds = time.perf_counter() - t
            cpu_seconds = time.process_time() - c
            rows.append({"spp": spp, "seconds": seconds, "cpu_seconds": cpu_seconds,
                         "rel_mse": rel_mse(image[..., :3], reference)})
            print(f"  mitsuba {variant} {scene_name} {spp:5d} spp: {seconds:7.2f} s, relMSE {rows[-1]['rel_mse']:.5f}", flush=True)
        if floor_spp > 0:
            # Seeds no row above uses, so the two renders are independent of them and of each other.
            pair = [np.array(mi.render(scene, spp=floor_spp, seed=100_003 + i), dtype=np.float64)[..., :3] for i in range(2)]
            floor = reference_floor(pair[0], pair[1], reference)
            floor["spp"] = floor_spp
            floor["rel_mse"] = [rel_mse(m, reference) for m in pair]
            print(f"  mitsuba {variant} {scene_name} reference floor from two {floor_spp}-spp renders: "
                  f"{floor['floor']:.6f} +- {floor['stderr']:.6f}", flush=True)
    return rows, floor


def reference_floor(m1, m2, reference):
    """The reference's own variance in relMSE's units, from two independent unbiased renders:
    E[(m1 - r)(m2 - r)] = Var(r) per pixel, the renders' own noise cancelling out."""
    import numpy as np

    # Per pixel (the channels' noise is correlated), so the standard error is not understated.
    products = ((m1 - reference) * (m2 - reference) / (reference**2 + 0.01)).mean(axis=-1)
    return {"floor": float(products.mean()), "stderr": float(products.std() / np.sqrt(products.size))}


def fit_mitsuba(rows, floor=0.0):
    """relMSE = k / spp + floor (k: geometric mean of (relMSE - floor) * spp) and seconds = t0 + c * spp."""
    import numpy as np

    spp = np.array([r["spp"] for r in rows], dtype=np.float64)
    err = np.array([r["rel_mse"] for r in rows])
    k = float(np.exp(np.mean(np.log(np.maximum(err - floor, 1e-12) * spp))))
    k_no_floor = float(np.exp(np.mean(np.log(err * spp))))

    def line(key):
        sec = np.array([r[key] for r in rows])
        if len(rows) > 1:
            c, t0 = np.polyfit(spp, sec, 1)
        else:
            c, t0 = sec[0] / spp[0], 0.0
        return float(c), float(max(t0, 0.0))

    c, t0 = line("seconds")
    cpu_c, cpu_t0 = line("cpu_seconds")
    return {"k": k, "floor": floor, "k_no_floor": k_no_floor, "c": c, "t0": t0, "cpu_c": cpu_c, "cpu_t0": cpu_t0}


def mitsuba_time_for(fit, error, cpu=False, floor=True):
    """Mitsuba's time to reach `error` against the reference; infinite at or below the floor."""
    excess = error - fit["floor"] if floor else error
    if excess <= 0:
        return float("inf"), float("inf")
    spp = (fit["k"] if floor else fit["k_no_floor"]) / excess
    if cpu:
        return fit["cpu_t0"] + fit["cpu_c"] * spp, spp
    return fit["t0"] + fit["c"] * spp, spp


# ---------------------------------------------------------------------------------------------
# Photonix


def run_photonix(binary, scene_name, backend, budget, reference, out_dir, extra, named=False):
    scene = REPO / "scenes" / f"{scene_name}.toml"
    out = Path(out_dir) / f"{scene_name}-{backend}-{budget}s.exr"
    # With several binaries, a row's backend column also names the binary.
    label = f"{backend} ({binary.name})" if named else backend
    cmd = [str(binary), "render", str(scene), "--backend", backend, "--time", f"{budget}s", "-o", str(out)] + extra
    t = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu_seconds = (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime)
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{proc.stderr}")
    passes = re.search(r"^(\d+) pass", proc.stderr, re.M)
    # The integrator `auto` chose (the default), named in the row.
    chosen = re.search(r"^integrator (\w+) \(automatic", proc.stderr, re.M)
    args = " ".join(extra + ([f"(auto: {chosen.group(1)})"] if chosen else []))
    image = read_exr(out)
    row = {
        "backend": label,
        "args": args,
        "budget": budget,
        "seconds": seconds,
        "cpu_seconds": cpu_seconds,
        "passes": int(passes.group(1)) if passes else None,
        "rel_mse": rel_mse(image, reference),
        "mean_ratio": mean_ratio(image, reference),
        "summary": proc.stderr.strip().splitlines()[-3:],
    }
    print(f"  photonix {label} {args} {scene_name} budget {budget} s: {seconds:6.2f} s, {row['passes']} passes, relMSE {row['rel_mse']:.5f}", flush=True)
    return row


# ---------------------------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scenes", default="cornell-box,cornell-caustics")
    ap.add_argument("--backends", default="gpu,cpu", help="Photonix backends (gpu = the Vulkan kernels)")
    ap.add_argument("--budgets", default="30", help="Photonix time budgets in seconds, comma-separated")
    ap.add_argument("--spp", default="16,64,256", help="Mitsuba sample counts, comma-separated")
    ap.add_argument("--variant", default=None, help="Mitsuba variant [default: llvm_ad_rgb, else scalar_rgb]")
    ap.add_argument("--max-depth", type=int, default=65, help="Mitsuba path depth (the references used 65)")
    ap.add_argument(
        "--photonix",
        action="append",
        help="photonix binary [default: target/release/photonix]; repeat to compare builds in one run "
        "(rows named by the binary's file name)",
    )
    ap.add_argument(
        "--photonix-args",
        action="append",
        help="extra flags for `photonix render`, e.g. '--gather-rays 2'; repeat to measure variants in one run "
        "('' for the defaults)",
    )
    ap.add_argument("--floor-spp", type=int, default=1024,
                    help="Mitsuba samples of each of the two renders that measure the reference's noise floor (0: no floor)")
    ap.add_argument("--no-mitsuba", action="store_true", help="Photonix only (no ratios)")
    ap.add_argument("--json", help="also write every measurement to this file")
    args = ap.parse_args()

    binaries = [Path(b) for b in args.photonix or [REPO / "target" / "release" / "photonix"]]
    binary = binaries[0]
    if not all(b.exists() for b in binaries):
        sys.exit(f"{binary} not found; run `cargo build --release` first")
    variant = choose_variant(args.variant)
    import mitsuba as mi

    scenes = args.scenes.split(",")
    budgets = [float(b) if "." in b else int(b) for b in args.budgets.split(",")]
    spps = [int(s) for s in args.spp.split(",")]
    version = subprocess.run([str(binary), "--version"], capture_output=True, text=True).stdout.strip()
    print(f"# time to quality, {time.strftime('%Y-%m-%d %H:%M')}, {platform.node()}, {os.cpu_count()} CPUs, "
          f"{version}, mitsuba {mi.__version__} {variant}")
    print(f"# command: {' '.join([Path(sys.argv[0]).name] + sys.argv[1:])}")

    results = {}
    with tempfile.TemporaryDirectory() as out_dir:
        for scene in scenes:
            reference = read_exr(REFERENCES / scene / "reference.exr")
            ours = [
                run_photonix(binary, scene, b, t, reference, out_dir, extra.split(), len(binaries) > 1)
                for binary in binaries
                for extra in args.photonix_args or [""]
                for b in args.backends.split(",")
                for t in budgets
            ]
            if args.no_mitsuba:
                continue
            theirs, floor = run_mitsuba(scene, spps, variant, reference, args.max_depth, args.floor_spp)
            fit = fit_mitsuba(theirs, floor["floor"] if floor else 0.0)
            results[scene] = {"photonix": ours, "mitsuba": theirs, "floor": floor, "fit": fit}

    print()
    print("| scene | renderer | budget | seconds | CPU seconds | passes / spp | relMSE | mean ratio R, G, B | Mitsuba s for this relMSE (spp) | equal-error ratio | CPU-time ratio | ratio without the floor |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for scene, r in results.items():
        fit = r["fit"]
        for m in r["mitsuba"]:
            print(f"| {scene} | mitsuba {variant} | - | {m['seconds']:.2f} | {m['cpu_seconds']:.2f} | {m['spp']} spp | "
                  f"{m['rel_mse']:.5f} | - | - | - | - | - |")
        for p in r["photonix"]:
            t_mi, spp = mitsuba_time_for(fit, p["rel_mse"])
            p["mitsuba_seconds"], p["ratio"] = t_mi, t_mi / p["seconds"]
            cpu_mi, _ = mitsuba_time_for(fit, p["rel_mse"], cpu=True)
            p["mitsuba_cpu_seconds"], p["cpu_ratio"] = cpu_mi, cpu_mi / p["cpu_seconds"]
            plain, _ = mitsuba_time_for(fit, p["rel_mse"], floor=False)
            p["ratio_no_floor"] = plain / p["seconds"]
            ratio = ", ".join(f"{r:.4f}" for r in p["mean_ratio"])
            name = f"photonix {p['backend']} {p['args']}".strip()
            print(f"| {scene} | {name} | {p['budget']} s | {p['seconds']:.2f} | {p['cpu_seconds']:.2f} | {p['passes']} passes | "
                  f"{p['rel_mse']:.5f} | {ratio} | {t_mi:.1f} ({spp:.0f} spp) | **{p['ratio']:.2f}** | {p['cpu_ratio']:.2f} | "
                  f"{p['ratio_no_floor']:.2f} |")
        print(f"| {scene} | mitsuba fit | | t = {fit['t0']:.2f} + {fit['c'] * 1000:.2f} ms x spp | "
              f"CPU t = {fit['cpu_t0']:.2f} + {fit['cpu_c'] * 1000:.2f} ms x spp | | relMSE = {fit['k']:.3f} / spp + {fit['floor']:.6f} | | | | | |")
        if r.get("floor"):
            f = r["floor"]
            print(f"| {scene} | reference floor | | | | 2 x {f['spp']} spp | {f['rel_mse'][0]:.5f}, {f['rel_mse'][1]:.5f} | | "
                  f"floor {f['floor']:.6f} +- {f['stderr']:.6f} | | | |")
    if args.json:
        Path(args.json).write_text(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
