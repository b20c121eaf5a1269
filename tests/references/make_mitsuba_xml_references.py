#!/usr/bin/env python3
"""Renders the Mitsuba scenes of tests/mitsuba/ with Mitsuba 3 into mitsuba/xml-<name>.exr, and
writes the small images they use (tests/mitsuba/sky.exr, tiles.png).

tests/mitsuba_scene.rs renders the same XML files through Photonix's Mitsuba front-end and
compares: here the file is the scene, so nothing is translated by hand.

With --rooms it renders the three rooms of ../shared/real-scenes/ at 32x18 into
mitsuba/room-<name>.exr instead (Modern Hall's Tungsten image shows another view, so these are
the rooms' pixel references at that size). Mitsuba 3 refuses a few Mitsuba 0.5 properties;
they are dropped from the text first, as that folder's README says.

    pip install mitsuba            # 3.9.1 made the committed files
    python3 tests/references/make_mitsuba_xml_references.py [--spp 4096] [names...]
    python3 tests/references/make_mitsuba_xml_references.py --rooms [--spp 1024]
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


ROOMS = ["veach-ajar", "modern-hall", "grey-white-room"]
DROPPED = ["high_quality_edges", "fileFormat", "pixelFormat", "banner", "filterType", "file_format", "pixel_format"]


def render_room(mi, name, spp):
    import re
    folder = os.path.join(HERE, "..", "..", "..", "shared", "real-scenes", name)
    text = open(os.path.join(folder, "scene.xml")).read()
    for p in DROPPED:
        text = re.sub(r'<[a-z]+ name="%s"[^>]*/>' % p, "", text)
    text = re.sub(r'name="width" value="[^"]*"', 'name="width" value="32"', text)
    text = re.sub(r'name="height" value="[^"]*"', 'name="height" value="18"', text)
    text = text.replace('value="$resx"', 'value="32"').replace('value="$resy"', 'value="18"')
    mi.file_resolver().prepend(folder)
    scene = mi.load_string(text)
    image = mi.render(scene, spp=spp)
    out = os.path.join(HERE, "mitsuba", f"room-{name}.exr")
    mi.Bitmap(image).write(out)
    print("wrote", out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("--rooms", action="store_true")
    ap.add_argument("names", nargs="*", default=["conventions"])
    args = ap.parse_args()
    import mitsuba as mi
    mi.set_variant("scalar_rgb")
    if args.rooms:
        os.makedirs(os.path.join(HERE, "mitsuba"), exist_ok=True)
        for name in args.names if args.names != ["conventions"] else ROOMS:
            render_room(mi, name, args.spp)
        return
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
