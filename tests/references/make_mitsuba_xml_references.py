#!/usr/bin/env python3
"""Renders the Mitsuba scenes of tests/mitsuba/ with Mitsuba 3 into mitsuba/xml-<name>.exr, and
writes the small images they use (tests/mitsuba/sky.exr, tiles.png).

tests/mitsuba_scene.rs renders the same XML files through Photonix's Mitsuba front-end and
compares: here the file is the scene, so nothing is translated by hand.

    pip install mitsuba            # 3.9.1 made the committed files
    python3 tests/references/make_mitsuba_xml_references.py [--spp 4096] [names...]
"""
import argparse
import os

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
SCENES = os.path.join(HERE, "..", "mitsuba")


def write_inputs(mi):
    # An environment whose colour tells every direction apart: red grows along u (around +y),
    # green along v (from the top down), blue constant.
    w, h = 64, 32
    u = (np.arange(w) + 0.5) / w
    v = (np.arange(h) + 0.5) / h
    sky = np.zeros((h, w, 3), dtype=np.float32)
    sky[..., 0] = 2.0 * u[None, :]
    sky[..., 1] = 1.5 * (1.0 - v[:, None])
    sky[..., 2] = 0.4
    mi.Bitmap(sky).write(os.path.join(SCENES, "sky.exr"))
    # 4 x 4 tiles, each its own colour: a flipped or mirrored lookup moves them.
    tiles = np.zeros((4, 4, 3), dtype=np.uint8)
    for j in range(4):
        for i in range(4):
            tiles[j, i] = (40 + 60 * i, 40 + 60 * j, 200 - 40 * ((i + j) % 4))
    mi.Bitmap(tiles).write(os.path.join(SCENES, "tiles.png"))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("names", nargs="*", default=["conventions"])
    args = ap.parse_args()
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    write_inputs(mi)
    os.makedirs(os.path.join(HERE, "mitsuba"), exist_ok=True)
    for name in args.names:
        scene = mi.load_file(os.path.join(SCENES, f"{name}.xml"), spp=args.spp)
        image = mi.render(scene, spp=args.spp)
        out = os.path.join(HERE, "mitsuba", f"xml-{name}.exr")
        mi.Bitmap(image).write(out)
        print("wrote", out)


if __name__ == "__main__":
    main()
