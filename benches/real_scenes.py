#!/usr/bin/env python3
"""Real interiors: Photonix against Mitsuba 3 on Bitterli's rooms (../shared/real-scenes/).

For each room this
  1. renders the room's unmodified scene.xml with Photonix (its Mitsuba front-end, docs/mitsuba.md)
     under each time budget, on each backend, with `auto` and with each integrator named, at a
     reduced resolution (default 320x180, a quarter of the files' 1280x720 on each axis), timing
     the whole command;
  2. renders the same file with Mitsuba 3's path tracer (the file's own integrator settings and
     reconstruction filter; only the Mitsuba 0.5 properties that Mitsuba 3 refuses are dropped and
     the film's size set) at several sample counts, timing mi.render after an untimed warm-up;
  3. measures every image against two truths: Bitterli's converged Tungsten render averaged down
     by whole factors (not for Modern Hall, whose Tungsten image is framed differently), and a long
     Mitsuba render (`--truth-spp`, cached in target/real-scenes/ by room, resolution, seed and
     sample count, since it takes minutes);
  4. for each truth, measures its own error against the ideal image (the floor: two independent
     Mitsuba renders m1, m2 give E[(m1 - t)(m2 - t)] = the truth's variance plus its squared
     bias, in relMSE's units; the method of benches/time_to_quality.py), fits Mitsuba's error as
     k / spp + floor and its time as t0 + c spp, and prints for each Photonix render the time
     Mitsuba needs for the same error divided by Photonix's (above 1: Photonix is faster), in wall
     and CPU time, with Mitsuba's ms/spp beside it (a ratio carries its host).

Needs a release build and `ci/setup --bench` (Mitsuba 3.9.1 and LLVM 19 in target/bench-tools):

    target/bench-tools/bin/python benches/real_scenes.py                       # every room, cpu, 60 s
    target/bench-tools/bin/python benches/real_scenes.py --rooms veach-ajar --budgets 30,60 \\
        --backends cpu,gpu --integrators auto,pt,bpt,vcm

Slow by design (tens of minutes): never run in CI.
"""

import argparse
import os
import platform
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from time_to_quality import (  # noqa: E402  (the same metric, fit and floor as the Cornell bench)
    choose_variant,
    fit_mitsuba,
    mean_ratio,
    mitsuba_time_for,
    read_exr,
    reference_floor,
    rel_mse,
)

REPO = Path(__file__).resolve().parent.parent
ROOMS = REPO.parent / "shared" / "real-scenes"
CACHE = REPO / "target" / "real-scenes"

# Mitsuba 0.5 properties that Mitsuba 3 refuses (../shared/real-scenes/README.md).
REFUSED = ("high_quality_edges", "fileFormat", "pixelFormat", "banner", "filterType")

# Rooms whose Tungsten image frames the scene as scene.xml does.
TUNGSTEN_FRAMED = {"veach-ajar", "grey-white-room"}


# ---------------------------------------------------------------------------------------------
# Mitsuba 3: the room's own file


def mitsuba_xml(room, width, height):
    """scene.xml as Mitsuba 3 reads it: the refused properties dropped, the film's size set."""
    text = (ROOMS / room / "scene.xml").read_text()
    for name in REFUSED:
        text = re.sub(r'<[a-z]+ name="%s"[^>]*/>' % name, "", text)
    text = re.sub(r'(<integer name="width" value=")\d+', r"\g<1>%d" % width, text)
    text = re.sub(r'(<integer name="height" value=")\d+', r"\g<1>%d" % height, text)
    # Mitsuba 3 files set the size through defaults ($resx, $resy).
    text = re.sub(r'(<default name="resx" value=")\d+', r"\g<1>%d" % width, text)
    text = re.sub(r'(<default name="resy" value=")\d+', r"\g<1>%d" % height, text)
    return text


def load_room(room, width, height):
    import mitsuba as mi

    # The meshes and textures are named relative to the room's folder; the patched file lives
    # in a temporary folder, so the room's folder goes first on the resolver's path.
    mi.Thread.thread().file_resolver().prepend(str(ROOMS / room))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.xml"
        path.write_text(mitsuba_xml(room, width, height))
        return mi.load_file(str(path))


def mitsuba_render(scene, spp, seed):
    import numpy as np
    import mitsuba as mi

    t = time.perf_counter()
    c = time.process_time()
    image = np.array(mi.render(scene, spp=spp, seed=seed), dtype=np.float64)[..., :3]
    return image, time.perf_counter() - t, time.process_time() - c


def long_mitsuba(room, scene, width, height, spp, variant):
    """The long render used as a truth, cached (it is the same bytes for the same inputs)."""
    import mitsuba as mi

    CACHE.mkdir(parents=True, exist_ok=True)
    path = CACHE / f"{room}-{width}x{height}-{variant}-{spp}spp-seed7.exr"
    if not path.exists():
        print(f"  mitsuba {room}: long render at {spp} spp for the truth (cached in {path})", flush=True)
        image, seconds, _ = mitsuba_render(scene, spp, 7)
        mi.Bitmap(image.astype("float32")).write(str(path))
        print(f"  mitsuba {room}: {seconds:.0f} s", flush=True)
    return read_exr(path)


def downsample(image, width, height):
    """Whole-factor box average (the Tungsten renders are 1280x720)."""
    h, w = image.shape[:2]
    if w % width or h % height or w // width != h // height:
        sys.exit(f"the reference's {w}x{h} is no whole multiple of {width}x{height}")
    f = w // width
    return image.reshape(height, f, width, f, 3).mean(axis=(1, 3))


# ---------------------------------------------------------------------------------------------
# Photonix


def run_photonix(binary, room, backend, integrator, budget, width, height, out_dir):
    out = Path(out_dir) / f"{room}-{backend}-{integrator}-{budget}s.exr"
    cmd = [str(binary), "render", str(ROOMS / room / "scene.xml"), "--backend", backend,
           "--time", f"{budget}s", "--resolution", f"{width}x{height}", "-o", str(out)]
    if integrator != "auto":
        cmd += ["--integrator", integrator]
    t = time.perf_counter()
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    proc = subprocess.run(cmd, capture_output=True, text=True)
    seconds = time.perf_counter() - t
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if proc.returncode != 0:
        print(f"  photonix {room} {backend} {integrator}: failed: {proc.stderr.strip()[-400:]}", flush=True)
        return None
    chosen = re.search(r"^integrator (\w+) \(automatic", proc.stderr, re.M)
    passes = re.search(r"^(\d+) pass", proc.stderr, re.M)
    name = f"auto ({chosen.group(1)})" if chosen else integrator
    row = {"backend": backend, "integrator": name, "budget": budget, "seconds": seconds,
           "cpu_seconds": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime),
           "passes": int(passes.group(1)) if passes else None, "image": read_exr(out)}
    print(f"  photonix {room} {backend} {name} {budget} s: {seconds:.1f} s, {row['passes']} passes", flush=True)
    return row


# ---------------------------------------------------------------------------------------------


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--rooms", default="veach-ajar,modern-hall,grey-white-room")
    ap.add_argument("--backends", default="cpu", help="Photonix backends (gpu: the Vulkan kernels, lavapipe here)")
    ap.add_argument("--integrators", default="auto,pt,bpt,vcm", help="Photonix integrators ('auto': its choice)")
    ap.add_argument("--budgets", default="60", help="Photonix time budgets in seconds, comma-separated")
    ap.add_argument("--resolution", default="320x180")
    ap.add_argument("--spp", default="4,16,64", help="Mitsuba sample counts for its fit, comma-separated")
    ap.add_argument("--truth-spp", type=int, default=4096, help="samples of the long Mitsuba render used as a truth")
    ap.add_argument("--floor-spp", type=int, default=256, help="samples of each of the two renders that measure a truth's floor")
    ap.add_argument("--variant", default=None, help="Mitsuba variant [default: llvm_ad_rgb, else scalar_rgb]")
    ap.add_argument("--photonix", default=str(REPO / "target" / "release" / "photonix"))
    args = ap.parse_args()

    binary = Path(args.photonix)
    if not binary.exists():
        sys.exit(f"{binary} not found; run `cargo build --release` first")
    width, height = (int(v) for v in args.resolution.split("x"))
    variant = choose_variant(args.variant)
    import mitsuba as mi

    spps = [int(s) for s in args.spp.split(",")]
    version = subprocess.run([str(binary), "--version"], capture_output=True, text=True).stdout.strip()
    print(f"# real scenes, {time.strftime('%Y-%m-%d %H:%M')}, {platform.node()}, {os.cpu_count()} CPUs, "
          f"load {os.getloadavg()[0]:.2f}, {version}, mitsuba {mi.__version__} {variant}")
    print(f"# command: {' '.join([Path(sys.argv[0]).name] + sys.argv[1:])}")

    table = []
    with tempfile.TemporaryDirectory() as out_dir:
        for room in args.rooms.split(","):
            ours = [
                run_photonix(binary, room, b, i, t, width, height, out_dir)
                for b in args.backends.split(",")
                for i in args.integrators.split(",")
                for t in [float(x) if "." in x else int(x) for x in args.budgets.split(",")]
            ]
            scene = load_room(room, width, height)
            mitsuba_render(scene, 1, 999)  # warm-up: compiles the kernels, untimed
            renders = [(spp,) + mitsuba_render(scene, spp, spp) for spp in spps]
            pair = [mitsuba_render(scene, args.floor_spp, 100_003 + i)[0] for i in range(2)]
            truths = {}
            if room in TUNGSTEN_FRAMED:
                truths["Tungsten"] = downsample(read_exr(ROOMS / room / "TungstenRender.exr"), width, height)
            truths[f"Mitsuba {args.truth_spp} spp"] = long_mitsuba(room, scene, width, height, args.truth_spp, variant)
            for truth_name, truth in truths.items():
                floor = reference_floor(pair[0], pair[1], truth)["floor"]
                rows = [{"spp": s, "seconds": sec, "cpu_seconds": cpu, "rel_mse": rel_mse(img, truth)}
                        for s, img, sec, cpu in renders]
                fit = fit_mitsuba(rows, floor)
                for m in rows:
                    table.append(f"| {room} | {truth_name} | mitsuba {variant} | - | {m['seconds']:.1f} | "
                                 f"{m['cpu_seconds']:.1f} | {m['spp']} spp | {m['rel_mse']:.4f} | "
                                 f"{', '.join(f'{r:.3f}' for r in mean_ratio(renders[-1][1], truth)) if m is rows[-1] else '-'} | - | - | - |")
                for p in filter(None, ours):
                    error = rel_mse(p["image"], truth)
                    t_mi, spp = mitsuba_time_for(fit, error)
                    cpu_mi, _ = mitsuba_time_for(fit, error, cpu=True)
                    ratio = ", ".join(f"{r:.3f}" for r in mean_ratio(p["image"], truth))
                    table.append(f"| {room} | {truth_name} | photonix {p['backend']} {p['integrator']} | {p['budget']} s | "
                                 f"{p['seconds']:.1f} | {p['cpu_seconds']:.1f} | {p['passes']} passes | {error:.4f} | {ratio} | "
                                 f"{t_mi:.1f} ({spp:.0f} spp) | **{t_mi / p['seconds']:.2f}** | {cpu_mi / p['cpu_seconds']:.2f} |")
                table.append(f"| {room} | {truth_name} | mitsuba fit | | {fit['c'] * 1000:.1f} ms/spp + {fit['t0']:.1f} s | "
                             f"{fit['cpu_c'] * 1000:.1f} ms/spp | | {fit['k']:.3f} / spp + {floor:.5f} | | | | |")

    print()
    print("| room | truth | renderer | budget | seconds | CPU seconds | passes / spp | relMSE | mean ratio R, G, B | "
          "Mitsuba s for this relMSE (spp) | equal-error ratio | CPU-time ratio |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    print("\n".join(table))


if __name__ == "__main__":
    main()
