# %% [markdown]
# # Photonix from Python
# A notebook-style script (cells marked `# %%`, runnable in Jupyter, VS Code or as a plain
# script): load the Cornell box, render it into a numpy array, change a material and a light by
# their scene paths, compare, and render a scene in parts that merge into the same image.
#
# Install the package first (see README.md, "Python"): `pip install target/wheels/photonix-*.whl`.
# Run from the repository root: `python examples/notebook.py`.

# %%
import pathlib
import tempfile

import numpy as np

import photonix

scene = photonix.load("scenes/cornell-box.toml")
print(scene, "devices:", [d["name"] for d in photonix.devices()])

# %% [markdown]
# ## Render to an array
# `render` takes the command line's options as keyword arguments; `info` gets what happened.

# %%
info = {}
image = photonix.render(
    scene, passes=4, resolution=(128, 128), progress=lambda p: print(f"\r{p}", end=""), info=info
)
print(f"\n{image.shape} {image.dtype}; {info['passes']} passes on {info['device']} in {info['seconds']:.2f} s")
print("mean radiance (R, G, B):", image.mean(axis=(0, 1)))
photonix.write_image("box.png", image)

# %% [markdown]
# ## Change the scene by path
# Any value of the scene file: `materials.<name>.<field>`, `camera.<field>`, `lights[<index or
# name>].<field>`, `shapes[<index or name>].<field>`. An edit the parser refuses raises
# `photonix.SceneError` with the file:line:column, and changes nothing.

# %%
blue = scene.copy()
blue["materials.red.reflectance"] = [0.05, 0.1, 0.7]
blue["lights[ceiling light].radiance"] = [12, 12, 12]
image_blue = photonix.render(blue, passes=4, resolution=(128, 128))
left_wall = np.s_[:, :16]
print("left wall before:", image[left_wall].mean(axis=(0, 1)), "after:", image_blue[left_wall].mean(axis=(0, 1)))
try:
    blue["materials.red.reflectance"] = [0.5, 0.5]  # two channels: refused
except photonix.SceneError as e:
    print("refused:", e)

# %% [markdown]
# ## The layers
# `layers=True` returns the four terms and their sum.

# %%
layers = photonix.render(scene, passes=2, resolution=(96, 96), layers=True)
for name, layer in layers.items():
    print(f"{name:>9}: mean {layer.mean():.4f}")
photonix.write_image("box-layers.exr", layers)

# %% [markdown]
# ## A render in parts
# Each part renders its own pass range into an accumulation file (as `photonix render
# --pass-range` does on a farm, see docs/progressive.md); `merge` sums them. With one pass per
# part the merge adds the passes in the same order as one render of all of them, so the
# images are identical to the bit.

# %%
with tempfile.TemporaryDirectory() as folder:
    parts = [pathlib.Path(folder) / f"part-{i}.exr" for i in range(4)]
    for i, part in enumerate(parts):
        photonix.render(scene, pass_range=(i, i + 1), resolution=(64, 64), accumulation=part)
    merged = photonix.merge(parts)
whole = photonix.render(scene, passes=4, resolution=(64, 64))
print("merged parts equal the whole render:", np.array_equal(merged, whole))
