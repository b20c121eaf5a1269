#!/usr/bin/env python3
"""Writes a scene with one generated mesh of about 3.5 M triangles (a rippled heightfield, smooth:
the mesh's default `smooth_angle` gives its triangles vertex normals, so each also gets a
shading block) into DIR: DIR/terrain.obj (140 MB, under the 256 MiB an OBJ may take) and
DIR/scene.toml. Its primitives (64 bytes each, 214 MiB) and shading data (60 bytes each,
200 MiB) exceed one lavapipe binding (128 MiB), so the GPU backend must page them.

    python3 benches/large_mesh/generate.py /tmp/large-mesh [quads-per-side]

1323 quads a side (the default) make 2 * 1323^2 = 3,500,658 triangles; benches/large_mesh/run.sh
renders the scene on both backends."""
import math
import sys
from pathlib import Path

out = Path(sys.argv[1] if len(sys.argv) > 1 else "/tmp/large-mesh")
n = int(sys.argv[2]) if len(sys.argv) > 2 else 1323
out.mkdir(parents=True, exist_ok=True)


def height(x, z):
    return 0.08 * math.sin(9 * x) * math.cos(7 * z) + 0.03 * math.sin(31 * x + 17 * z)


with open(out / "terrain.obj", "w") as f:
    f.write(f"# {2 * n * n} triangles, benches/large_mesh/generate.py\n")
    for i in range(n + 1):
        z = -1 + 2 * i / n
        f.write("".join(f"v {-1 + 2 * j / n:.6f} {height(-1 + 2 * j / n, z):.5f} {z:.6f}\n" for j in range(n + 1)))
    for i in range(n):
        rows = []
        for j in range(n):
            a = i * (n + 1) + j + 1
            b, c, d = a + 1, a + n + 1, a + n + 2
            # Counter-clockwise seen from above (+y): the winding normal points up.
            rows.append(f"f {a} {c} {b}\nf {b} {c} {d}\n")
        f.write("".join(rows))

(out / "scene.toml").write_text(
    """# A generated heightfield of about 3.5 M smooth triangles under a square light
# (benches/large_mesh/generate.py).
[camera]
position = [0, 1.6, 2.4]
look_at = [0, 0, 0]
fov = 45
resolution = [128, 128]

[render]
spp = 1
passes = 1
max_depth = 6
seed = 0

[photons]
count = 100000
caustic_count = 1000
gather_rays = 0

[materials.ground]
type = "diffuse"
reflectance = [0.6, 0.55, 0.5]

[materials.lamp]
type = "diffuse"
reflectance = 0
emission = [12, 12, 12]

[[shapes]]
type = "mesh"
file = "terrain.obj"
material = "ground"

[[shapes]]
type = "quad"
material = "lamp"
# Wound so that its normal points down, toward the terrain.
vertices = [[0.4, 2, -0.4], [0.4, 2, 0.4], [-0.4, 2, 0.4], [-0.4, 2, -0.4]]
"""
)
print(f"wrote {out}/terrain.obj ({2 * n * n} triangles) and {out}/scene.toml")
