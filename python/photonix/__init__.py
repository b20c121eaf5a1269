"""Photonix from Python: load a scene, change it, render it to a numpy array.

    import photonix
    scene = photonix.load("scenes/cornell-box.toml")        # or .pov, .glb, .gltf, .xml
    scene["materials.red.reflectance"] = [0.2, 0.2, 0.8]
    image = photonix.render(scene, passes=4, resolution=(128, 128))   # float32 (128, 128, 3)
    photonix.write_image("box.png", image)

    renderer = photonix.Renderer(scene, backend="gpu")      # the device set up once
    for r in (0.2, 0.5, 0.8):
        scene["materials.red.reflectance"] = [r, 0.1, 0.1]
        image = renderer.render(passes=4)                    # edits are picked up

`load_dict` builds a scene from a dict (the TOML schema as a dict), `traverse` lists every
scene path with its value and type and updates them in place, `Scene.add` and `Scene.remove`
add and remove shapes, lights and materials (compare Mitsuba 3's `load_file`, `load_dict`,
`traverse`).

The renderer is the one the `photonix` command runs (the Vulkan kernels, or their CPU twins),
driven through the library's API: `render` takes the command line's options, as keyword
arguments. It releases the GIL while it renders, reports progress to an optional callback, and
on Ctrl-C (KeyboardInterrupt) stops after the work under way and returns the mean of the passes
finished, with a RuntimeWarning saying how many.
"""

from __future__ import annotations

import collections.abc as _abc
import datetime as _datetime
import os as _os
from typing import Any, Callable, Dict, List, Literal, Mapping, Optional, Sequence, Tuple, Union, overload

import numpy as _np

from . import _photonix
from ._photonix import (
    MAX_PASSES,
    Cancelled,
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
    "Renderer",
    "SceneParameters",
    "Cancelled",
    "Progress",
    "PhotonixError",
    "SceneError",
    "RenderError",
    "ImageError",
    "MAX_PASSES",
    "load",
    "loads",
    "load_dict",
    "traverse",
    "render",
    "write_image",
    "read_image",
    "merge",
    "devices",
]

PathLike = Union[str, "_os.PathLike[str]"]


def load(path: PathLike, resolution: Optional[Tuple[int, int]] = None) -> Scene:
    """Reads a scene file through the front-end its extension names, as `photonix render`
    does: TOML (docs/scene-format.md), POV-Ray (.pov), glTF 2.0 (.gltf, .glb) or Mitsuba
    (.xml). A POV-Ray, glTF or Mitsuba scene is translated to TOML as `photonix convert`
    does, so it is edited like any other; `scene.source` is the file read, `scene.path` the
    TOML's name beside it (nothing is written). `resolution=(w, h)` sizes a POV-Ray scene
    (POV-Ray's +W +H, default 320x240) or a glTF camera.

    Mesh and texture paths are relative to the file's folder. Raises SceneError with the
    file:line:column of the problem and what to do about it.
    """
    size = None if resolution is None else (int(resolution[0]), int(resolution[1]))
    return _photonix.load(_os.fspath(path), size)


def load_dict(scene: Mapping[str, object], path: PathLike = "scene.toml") -> Scene:
    """Builds a scene from a dict in the TOML schema (docs/scene-format.md), as Mitsuba's
    `load_dict`: dicts are tables, lists of dicts arrays of tables, e.g.

        photonix.load_dict({
            "camera": {"position": [0, 1, 4], "look_at": [0, 1, 0], "fov": 40},
            "materials": {"white": {"type": "diffuse", "reflectance": [0.8, 0.8, 0.8]}},
            "shapes": [{"type": "sphere", "center": [0, 1, 0], "radius": 1, "material": "white"}],
            "lights": [{"type": "point", "position": [0, 3, 2], "intensity": [20, 20, 20]}],
        })

    `path` names the scene and is where relative mesh and texture paths are read from.
    Raises SceneError as for a file."""
    if not isinstance(scene, dict):
        scene = dict(scene)
    return _photonix.load_dict(scene, _os.fspath(path))


def _leaf_type(value: object) -> str:
    if isinstance(value, bool):
        return "bool"
    if isinstance(value, int):
        return "int"
    if isinstance(value, float):
        return "float"
    if isinstance(value, str):
        return "str"
    if isinstance(value, list):
        if value and all(isinstance(v, (int, float)) and not isinstance(v, bool) for v in value):
            return "list[float]" if any(isinstance(v, float) for v in value) else "list[int]"
        if value and all(isinstance(v, str) for v in value):
            return "list[str]"
        return "list"
    return type(value).__name__


class SceneParameters(_abc.Mapping):
    """Every value of a scene by its path, with its type, as Mitsuba's `traverse` gives:
    `params["materials.red.reflectance"]`, `params.type("shapes[floor].material")`. Setting
    `params[path] = value` stages a change; `update()` applies the staged changes to the scene
    in place, all at once (parsed once: on a SceneError none is applied), and returns the paths
    changed. Entries of arrays of tables go by their `name` where they have a unique one
    (`shapes[floor]`), else by position (`lights[0]`)."""

    def __init__(self, scene: Scene) -> None:
        self._scene = scene
        self._values: Dict[str, object] = {}
        self._types: Dict[str, str] = {}
        self._staged: Dict[str, object] = {}
        self._walk(scene.to_dict(), "")

    def _walk(self, node: object, prefix: str) -> None:
        if isinstance(node, dict):
            for key, value in node.items():
                self._walk(value, f"{prefix}.{key}" if prefix else key)
        elif isinstance(node, list) and node and all(isinstance(v, dict) for v in node):
            names = [v.get("name") for v in node]
            for i, entry in enumerate(node):
                name = entry.get("name")
                unique = isinstance(name, str) and names.count(name) == 1 and not name.isdigit()
                step = f"[{name}]" if unique else f"[{i}]"
                self._walk(entry, prefix + step)
        else:
            self._values[prefix] = node
            self._types[prefix] = _leaf_type(node)

    def __getitem__(self, path: str) -> object:
        if path in self._staged:
            return self._staged[path]
        return self._values[path]

    def __setitem__(self, path: str, value: object) -> None:
        if path not in self._values:
            raise KeyError(f"{path!r} is not a path of the scene; Scene.add adds new entries")
        self._staged[path] = value

    def __iter__(self):
        return iter(self._values)

    def __len__(self) -> int:
        return len(self._values)

    def type(self, path: str) -> str:
        """The type of the value at `path`: bool, int, float, str, list[float], list[int],
        list[str] or list."""
        return self._types[path]

    def update(self) -> List[str]:
        """Applies the staged changes to the scene in place and returns their paths."""
        changed = list(self._staged)
        if changed:
            self._scene.set_many([(p, v) for p, v in self._staged.items()])
            for path, value in self._staged.items():
                self._values[path] = value
                self._types[path] = _leaf_type(value)
            self._staged.clear()
        return changed

    def __repr__(self) -> str:
        lines = [f"SceneParameters[{len(self)}] of {self._scene!r}"]
        for path, value in self._values.items():
            lines.append(f"  {path:<40} {self._types[path]:<12} {value!r}")
        return "\n".join(lines)


def traverse(scene: Scene) -> SceneParameters:
    """Every scene path with its value and type (as Mitsuba's `mi.traverse`); change values
    with `params[path] = value` and apply them in place with `params.update()`."""
    return SceneParameters(scene)


def loads(text: str, path: PathLike = "scene.toml") -> Scene:
    """Parses scene text. `path` names it in error messages, gives the scene its name, and its
    folder is where relative mesh and texture paths are read from (the current folder by
    default)."""
    return _photonix.loads(text, _os.fspath(path))


class Renderer:
    """A renderer kept across renders of one scene: the backend is chosen, the device opened
    and the kernels made once, so a second render of the scene (edited or not) skips that
    set-up (on lavapipe seconds a call; `info["setup_seconds"]` says what each call spent).

        renderer = photonix.Renderer(scene, backend="gpu")
        image = renderer.render(passes=4, resolution=(64, 64))

    `render` takes `photonix.render`'s options but `backend` and `device`, and renders the
    scene as it is when the call starts: another thread may edit the scene meanwhile. Renders
    on one renderer run one at a time. `cancel()`, from any thread, stops the render under way
    after the submission in progress: it returns the mean of the passes finished
    (`info["stop_reason"] == "cancelled"`), or raises Cancelled when none had finished. Ctrl-C
    reaches a render on the main thread only (Python delivers signals there): a render on
    another thread is stopped with `cancel()`. `close()` (or a `with` block) frees the device.
    """

    def __init__(self, scene: Union[Scene, PathLike], backend: str = "auto", device: Union[None, int, str] = None):
        self.scene: Scene = scene if isinstance(scene, Scene) else load(scene)
        self._backend = backend
        self._device = None if device is None else str(device)
        self._core = _photonix.RendererCore(backend, self._device)

    @overload
    def render(self, *, layers: Literal[False] = False, **options: Any) -> _np.ndarray: ...

    @overload
    def render(self, *, layers: Literal[True], **options: Any) -> Dict[str, _np.ndarray]: ...

    def render(self, *, layers: bool = False, **options: Any) -> Union[_np.ndarray, Dict[str, _np.ndarray]]:
        """Renders `self.scene` with `photonix.render`'s options (not backend or device)."""
        for name in ("backend", "device"):
            if name in options:
                raise TypeError(f"{name} is chosen when the Renderer is made; make another Renderer for another")
        return render(
            self.scene, backend=self._backend, device=self._device, layers=layers, _renderer=self._core, **options
        )

    def cancel(self) -> None:
        """Stops the render under way (from any thread); nothing when none is."""
        self._core.cancel()

    def close(self) -> None:
        """Frees the device and the kernels; the renderer cannot render after."""
        self._core.close()

    def __enter__(self) -> "Renderer":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


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


# The return type follows `layers`: an array without, a dict of arrays with (for type checkers).
@overload
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
    layers: Literal[False] = False,
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
    _renderer: Optional[object] = None,
    denoise: Optional[bool] = None,
    aovs: Literal[False] = False,
    adaptive: Optional[bool] = None,
) -> _np.ndarray: ...


@overload
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
    layers: Literal[True],
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
    _renderer: Optional[object] = None,
    denoise: Optional[bool] = None,
    aovs: bool = False,
    adaptive: Optional[bool] = None,
) -> Dict[str, _np.ndarray]: ...


@overload
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
    _renderer: Optional[object] = None,
    denoise: Optional[bool] = None,
    aovs: bool = False,
    adaptive: Optional[bool] = None,
) -> Union[_np.ndarray, Dict[str, _np.ndarray]]: ...


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
    _renderer: Optional[object] = None,
    denoise: Optional[bool] = None,
    aovs: bool = False,
    adaptive: Optional[bool] = None,
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
                    error_estimate, backend, backend_reason, device, seconds, resolution, spp,
                    integrator (the one that rendered) and integrator_reason (why `auto`
                    chose it; None when it was named), setup_seconds (opening the device and
                    making the kernels), renderer_kept (a Renderer's kept kernels were used),
                    and denoise_seconds where denoised
      denoise       denoise with Intel Open Image Denoise, guided by albedo and normal layers
                    (None: the scene's [render] denoise); with layers=True the raw mean is
                    kept as "noisy". Needs the library: see docs/denoising.md
      aovs          also return the feature layers albedo, normal, depth, position in the
                    dict (implies the dict, as layers=True)
      adaptive      adaptive sampling: after 8 uniform passes, later passes render the half
                    of the pixels where one more pass lowers the error most (every 8th pass
                    all of them; None: the scene's [render] adaptive); see docs/progressive.md

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
        renderer=_renderer,
        denoise=denoise,
        aovs=aovs,
        adaptive=adaptive,
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
