#!/usr/bin/env python3
"""Denoising at a time budget: relMSE against the shared references of a raw render, the same
budget denoised (`--denoise`, its feature layers and the denoiser's time inside the budget), and
a raw render of a longer budget, on the four shared Cornell scenes, CPU backend by default.

Per scene it runs `photonix render --time B` (raw), `--time B --denoise --layers` (denoised; the
EXR's first layer is the denoised image, `noisy` the raw one) and `--time LONG` (raw), and prints
a Markdown table: relMSE as `photonix diff` computes it ((t - r)^2 / (r^2 + 0.01), mean over
pixels and channels), the ratios, and each channel's mean against the reference's. It also writes
sRGB PNG crops (raw | denoised | long raw | reference) for a look, into --png-dir.

Needs a release build, Open Image Denoise (ci/setup) and Mitsuba 3 for reading EXRs (ci/setup
--bench; run with target/bench-tools/bin/python). Slow by design: (2 B + LONG) per scene.

    target/bench-tools/bin/python benches/denoise.py --budget 30 --long 240
"""

import argparse
import re
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from time_to_quality import REFERENCES, REPO, read_exr, rel_mse  # noqa: E402


def render(binary, scene, backend, seconds, out, extra):
    cmd = [str(binary), "render", str(REPO / "scenes" / f"{scene}.toml"), "--backend", backend,
           "--time", f"{seconds}s", "-o", str(out)] + extra
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode != 0:
        sys.exit(f"{' '.join(cmd)} failed:\n{proc.stderr}")
    passes = int(re.search(r"^(\d+) pass", proc.stderr, re.M).group(1))
    denoise = re.search(r"denoise \((\w+)\) ([0-9.]+) s", proc.stderr)
    features = re.search(r"features ([0-9.]+) s", proc.stderr)
    return passes, (float(denoise.group(2)) if denoise else None), (float(features.group(1)) if features else None)


def means(test, ref):
    return [float(test[..., c].mean() / ref[..., c].mean()) for c in range(3)]


def to_png(images, path):
    import numpy as np
    import mitsuba as mi
    row = np.concatenate([np.clip(i, 0, None) for i in images], axis=1).astype(np.float32)
    mi.Bitmap(row, pixel_format=mi.Bitmap.PixelFormat.RGB).convert(
        mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.UInt8, srgb_gamma=True).write(str(path))


def flip_table(png_dir, scenes):
    """LDR FLIP (flip-evaluator, default 67 pixels per degree) of each sRGB PNG panel against the
    reference's panel, where `pip install flip-evaluator` (1.7 was used) and Pillow are there."""
    try:
        import numpy as np
        import flip_evaluator as flip
        from PIL import Image
    except ImportError:
        print("(no FLIP: pip install flip-evaluator pillow)", file=sys.stderr)
        return
    print("| scene | FLIP raw | FLIP denoised | FLIP raw long |")
    print("| --- | --- | --- | --- |")
    for scene in scenes:
        a = np.asarray(Image.open(Path(png_dir) / f"{scene}.png").convert("RGB")).astype(np.float32) / 255
        w = a.shape[1] // 4
        panels = [a[:, k * w:(k + 1) * w] for k in range(4)]
        values = [flip.evaluate(panels[3], panels[k], "LDR", applyMagma=False)[1] for k in range(3)]
        print(f"| {scene} | " + " | ".join(f"{v:.4f}" for v in values) + " |")
    print()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", default=str(REPO / "target" / "release" / "photonix"))
    ap.add_argument("--budget", type=float, default=30)
    ap.add_argument("--long", type=float, default=240)
    ap.add_argument("--backend", default="cpu")
    ap.add_argument("--scenes", default="cornell-box,cornell-caustics,cornell-glossy,cornell-fog")
    ap.add_argument("--png-dir", default=None)
    args = ap.parse_args()
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for scene in args.scenes.split(","):
            ref = read_exr(REFERENCES / scene / "reference.exr")
            out = {k: Path(tmp) / f"{scene}-{k}.exr" for k in ["raw", "denoised", "long"]}
            raw = render(args.binary, scene, args.backend, args.budget, out["raw"], [])
            den = render(args.binary, scene, args.backend, args.budget, out["denoised"], ["--denoise", "--layers"])
            long = render(args.binary, scene, args.backend, args.long, out["long"], [])
            img = {k: read_exr(p) for k, p in out.items()}
            err = {k: rel_mse(v, ref) for k, v in img.items()}
            rows.append((scene, raw, den, long, err, means(img["denoised"], ref), means(img["raw"], ref)))
            print(f"{scene}: relMSE raw {err['raw']:.3e}, denoised {err['denoised']:.3e}, "
                  f"raw {args.long:g} s {err['long']:.3e}", file=sys.stderr, flush=True)
            if args.png_dir:
                Path(args.png_dir).mkdir(parents=True, exist_ok=True)
                to_png([img["raw"], img["denoised"], img["long"], ref], Path(args.png_dir) / f"{scene}.png")
    if args.png_dir:
        flip_table(args.png_dir, [r[0] for r in rows])
    b, lb = f"{args.budget:g} s", f"{args.long:g} s"
    print(f"| scene | relMSE raw {b} (passes) | denoised {b} (passes; features s, denoise s) | raw {lb} (passes) "
          f"| raw / denoised | raw {lb} / denoised | denoised mean / reference R, G, B | raw mean / reference |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- |")
    for scene, raw, den, long, err, dm, rm in rows:
        print(f"| {scene} | {err['raw']:.3e} ({raw[0]}) | {err['denoised']:.3e} ({den[0]}; {den[2]:.1f}, {den[1]:.2f}) "
              f"| {err['long']:.3e} ({long[0]}) | {err['raw'] / err['denoised']:.1f}x | {err['long'] / err['denoised']:.2f}x "
              f"| {', '.join(f'{m:.4f}' for m in dm)} | {', '.join(f'{m:.4f}' for m in rm)} |")


if __name__ == "__main__":
    main()
