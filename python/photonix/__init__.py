"""Photonix from Python: load a scene, change it, render it to a numpy array.

    import photonix
    scene = photonix.load("scenes/cornell-box.toml")
    scene["materials.red.reflectance"] = [0.2, 0.2, 0.8]
    image = photonix.render(scene, passes=4, resolution=(128, 128))   # float32 (128, 128, 3)
    photonix.write_image("box.png", image)

The renderer is the one the `photonix` command runs (the Vulkan kernels, or their CPU twins),
driven through the library's API: `render` takes the command line's options, as keyword
arguments. It releases the GIL while it renders, reports progress to an optional callback, and
on Ctrl-C (KeyboardInterrupt) stops after the work under way and returns the mean of the passes
finished, with a RuntimeWarning saying how many.
"""

from __future__ import annotations

import datetime as _datetime
import os as _os
from typing import Callable, Dict, Mapping, Optional, Sequence, Tuple, Union

import numpy as _np

from . import _photonix
from ._photonix import (
    MAX_PASSES,
    ImageError,
    PhotonixError,
    Progress,
    RenderError,
    Scene,
    SceneError,
    devices,
)

__all__ = [
    "Scene",
    "Progress",
    "PhotonixError",
    "SceneError",
    "RenderError",
    "ImageError",
    "MAX_PASSES",
    "load",
    "loads",
    "render",
    "write_image",
    "read_image",
    "merge",
    "devices",
]

PathLike = Union[str, "_os.PathLike[str]"]


def load(path: PathLike) -> Scene:
    """Reads and parses a scene file (TOML, see docs/scene-format.md).

    Mesh and texture paths in it are relative to its folder. Raises SceneError with the
    file:line:column of the problem and what to do about it.
    """
    return _photonix.load(_os.fspath(path))


def loads(text: str, path: PathLike = "scene.toml") -> Scene:
    """Parses scene text. `path` names it in error messages, gives the scene its name, and its
    folder is where relative mesh and texture paths are read from (the current folder by
    default)."""
    return _photonix.loads(text, _os.fspath(path))


def _seconds(time: Union[None, float, int, _datetime.timedelta]) -> Optional[float]:
    if time is None:
        return None
    if isinstance(time, _datetime.timedelta):
        return time.total_seconds()
    return float(time)


def _pass_range(pass_range: Union[None, str, Sequence[int], range]) -> Optional[Tuple[int, int]]:
    if pass_range is None:
        return None
    if isinstance(pass_range, range):
        if pass_range.step != 1:
            raise ValueError(f"pass_range={pass_range!r} must have step 1")
        return (pass_range.start, pass_range.stop)
    if isinstance(pass_range, str):
        a, sep, b = pass_range.partition("..")
        if not sep:
            raise ValueError(f"pass_range={pass_range!r} is not A..B (e.g. '0..32')")
        return (int(a), int(b))
    a, b = pass_range
    return (int(a), int(b))


def render(
    scene: Union[Scene, PathLike],
    *,
    passes: Optional[int] = None,
    time: Union[None, float, _datetime.timedelta] = None,
    target_error: Optional[float] = None,
    seed: Optional[int] = None,
    backend: str = "auto",
    resolution: Optional[Tuple[int, int]] = None,
    pass_range: Union[None, str, Tuple[int, int], range] = None,
    layers: bool = False,
    spp: Optional[int] = None,
    max_depth: Optional[int] = None,
    photons: Optional[int] = None,
    caustic_photons: Optional[int] = None,
    radius: Optional[float] = None,
    caustic_radius: Optional[float] = None,
    gather_rays: Optional[int] = None,
    photon_depth: Optional[int] = None,
    no_photons: bool = False,
    device: Union[None, int, str] = None,
    accumulation: Optional[PathLike] = None,
    progress: Optional[Callable[[Progress], None]] = None,
    info: Optional[dict] = None,
    integrator: Optional[str] = None,
    denoise: Optional[bool] = None,
    aovs: bool = False,
) -> Union[_np.ndarray, Dict[str, _np.ndarray]]:
    """Renders `scene` (a Scene, or a path to a scene file) progressively and returns the mean
    of the passes: a float32 numpy array of shape (height, width, 3) holding linear radiance, or
    with `layers=True` a dict of such arrays: combined, direct, specular, indirect, caustics.

    The options are `photonix render`'s flags (see `photonix render --help`); None keeps the
    scene's value:
      passes        passes 0..passes (each traces its own photons with a smaller radius)
      time          seconds (or a timedelta): stop after the pass that crosses it
      target_error  stop when the estimated relMSE falls below it (needs 4 passes)
      seed, spp, max_depth, resolution=(width, height)
      integrator    "ppm" (progressive photon mapping), "pt" (path tracing with MIS), "bpt"
                    (bidirectional), "vcm" (vertex connection and merging) or "auto" (the
                    default: vcm for rough glossy surfaces under area lights or a sky, bpt
                    under point or spot lights and in media, else ppm; photon options choose
                    ppm); only ppm takes photon options, see docs/integrators.md
      backend       "auto" (a real GPU if there is one, else the CPU reference), "gpu" (the
                    Vulkan device even when it is lavapipe) or "cpu"
      pass_range    (A, B), range(A, B) or "A..B": exactly passes A..B-1, for farms
      photons, caustic_photons, radius, caustic_radius, gather_rays, photon_depth, no_photons
      device        Vulkan device index or name substring (see `devices()`)
      accumulation  also write the passes' sums as an accumulation file (.exr) that `merge`
                    (or `photonix merge`) combines with the other parts
      progress      called about every 50 ms while rendering with a Progress
                    (passes_done, passes_total, current_pass, pass_fraction, elapsed)
      info          a dict to fill with what happened: passes, pass_ranges, stop_reason,
                    error_estimate, backend, backend_reason, device, seconds, resolution, spp
                    (and denoise_seconds where denoised)
      denoise       denoise with Intel Open Image Denoise, guided by albedo and normal layers
                    (None: the scene's [render] denoise); with layers=True the raw mean is
                    kept as "noisy". Needs the library: see docs/denoising.md
      aovs          also return the feature layers albedo, normal, depth, position in the
                    dict (implies the dict, as layers=True)

    Raises SceneError (a scene the renderer cannot prepare), RenderError (refused before
    starting: memory, radii, device; or a device failure), ValueError (an option out of range)
    or what `progress` raised. On KeyboardInterrupt the render stops after the submission under
    way and returns the passes finished, warning with a RuntimeWarning; with none finished the
    KeyboardInterrupt is raised.
    """
    if not isinstance(scene, Scene):
        scene = load(scene)
    if isinstance(device, int):
        device = str(device)
    return _photonix.render(
        scene,
        passes=passes,
        time=_seconds(time),
        target_error=target_error,
        seed=seed,
        backend=backend,
        resolution=None if resolution is None else (int(resolution[0]), int(resolution[1])),
        pass_range=_pass_range(pass_range),
        layers=layers,
        spp=spp,
        max_depth=max_depth,
        photons=photons,
        caustic_photons=caustic_photons,
        radius=radius,
        caustic_radius=caustic_radius,
        gather_rays=gather_rays,
        photon_depth=photon_depth,
        no_photons=no_photons,
        device=device,
        accumulation=None if accumulation is None else _os.fspath(accumulation),
        progress=progress,
        info=info,
        integrator=integrator,
        denoise=denoise,
        aovs=aovs,
    )


def _as_image(array: object, what: str) -> _np.ndarray:
    image = _np.ascontiguousarray(array, dtype=_np.float32)
    if image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"{what} has shape {image.shape}; give an array of shape (height, width, 3)")
    return image


def write_image(
    path: PathLike, image: Union[_np.ndarray, Mapping[str, _np.ndarray]], exposure: float = 0.0
) -> None:
    """Writes linear radiance to `path`, atomically: an (height, width, 3) array as OpenEXR
    (.exr, float32) or 8-bit sRGB PNG (.png, scaled by 2**exposure first); a dict of such arrays
    (e.g. `render(..., layers=True)`) as the layers of one OpenEXR file."""
    path = _os.fspath(path)
    if isinstance(image, Mapping):
        if exposure != 0.0:
            raise ValueError("exposure scales PNG output only, and layers are written as EXR; leave it out")
        _photonix.write_layers(path, [(str(k), _as_image(v, f"layer {k!r}")) for k, v in image.items()])
    else:
        _photonix.write_image(path, _as_image(image, "the image"), float(exposure))


def read_image(path: PathLike) -> _np.ndarray:
    """Reads an OpenEXR image as a float32 (height, width, 3) array (an accumulation file reads
    as its mean image)."""
    return _photonix.read_image(_os.fspath(path))


def merge(
    parts: Sequence[PathLike],
    output: Optional[PathLike] = None,
    *,
    accumulation: bool = False,
    layers: bool = False,
    exposure: float = 0.0,
) -> Union[_np.ndarray, Dict[str, _np.ndarray]]:
    """Sums accumulation files of disjoint pass ranges, as `photonix merge` does, and returns the
    mean image (or with `layers=True` the dict of layers). Parts of different renders (scene,
    seed, settings), overlapping ranges or different sizes are refused with ImageError. With
    `output`, also writes the image there (.exr or .png), or with `accumulation=True` the merged
    accumulation file, for merging in stages."""
    return _photonix.merge(
        [_os.fspath(p) for p in parts],
        None if output is None else _os.fspath(output),
        accumulation=accumulation,
        layers=layers,
        exposure=float(exposure),
    )
