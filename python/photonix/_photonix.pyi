"""Type hints of the compiled module; photonix/__init__.py documents the functions."""

import os
import pathlib
from typing import Any, Callable, Dict, List, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

MAX_PASSES: int

class PhotonixError(Exception):
    """Base class of the errors Photonix raises."""

class SceneError(PhotonixError):
    """A scene that does not parse or an edit it refuses; the message has file:line:column."""

class RenderError(PhotonixError):
    """A render refused before it starts (memory, radii, device) or failed on the device."""

class ImageError(PhotonixError):
    """An image or accumulation file that cannot be read or written."""

class Cancelled(PhotonixError):
    """A render cancelled (Renderer.cancel) before its first pass finished."""

class Scene:
    """A scene: its TOML text, the file it came from, and the parsed scene. Edits go through
    the text and are parsed like any scene file; an edit the parser refuses changes nothing."""

    @property
    def toml(self) -> str:
        """The scene's TOML text, with every edit made so far."""
    @property
    def path(self) -> pathlib.Path:
        """The file the scene was read from (or named after, for `loads`)."""
    @property
    def source(self) -> pathlib.Path:
        """The file read: the TOML, or the POV-Ray, glTF or Mitsuba scene translated to it."""
    @property
    def name(self) -> str:
        """The file name without its extension."""
    @property
    def resolution(self) -> Tuple[int, int]:
        """The camera's image size as (width, height)."""
    @property
    def warnings(self) -> List[str]:
        """Warnings the parser gave."""
    def get(self, path: str) -> Any:
        """The value at a scene path: `materials.red.reflectance`, `camera.position`,
        `lights[0].radiance`, `shapes[floor].material` ([N] or [name] picks an entry of an
        array of tables). Raises KeyError naming what is there instead."""
    def set(self, path: str, value: Any) -> None:
        """Sets the value at a scene path (a number, bool, string, list, numpy array or dict;
        None removes the key) and parses the result; raises SceneError (file:line:column) and
        leaves the scene unchanged when the parser refuses it."""
    def set_many(self, edits: Sequence[Tuple[str, Any]]) -> None:
        """Sets several paths, parsing once: all change, or on an error none."""
    def add(self, path: str, value: Any) -> None:
        """Appends an entry to an array of tables (`shapes`, `lights`) or adds a new key
        (`materials.blue`)."""
    def remove(self, path: str) -> None:
        """Removes a key (`materials.blue`) or an array entry (`shapes[floor]`, `lights[0]`)."""
    def to_dict(self) -> Dict[str, Any]:
        """The whole scene as nested dicts and lists."""
    def __getitem__(self, path: str) -> Any: ...
    def __setitem__(self, path: str, value: Any) -> None: ...
    def copy(self) -> Scene:
        """A copy that can be edited without changing this one."""
    def save(self, path: "str | os.PathLike[str]") -> None:
        """Writes the TOML text to `path`."""

class Progress:
    """What the progress callback of `render` receives."""

    passes_done: int
    passes_total: int
    current_pass: int
    pass_fraction: float
    elapsed: float

class RendererCore:
    """The compiled half of photonix.Renderer: a render thread keeping the device and kernels."""

    def __init__(self, backend: str = "auto", device: Optional[str] = None) -> None: ...
    def cancel(self) -> None: ...
    def close(self) -> None: ...

def load(path: str, resolution: Optional[Tuple[int, int]] = None) -> Scene: ...
def load_dict(scene: Dict[str, Any], path: str = "scene.toml") -> Scene: ...
def loads(text: str, path: str = "scene.toml") -> Scene: ...
def render(
    scene: Scene,
    *,
    passes: Optional[int] = None,
    time: Optional[float] = None,
    target_error: Optional[float] = None,
    seed: Optional[int] = None,
    backend: str = "auto",
    resolution: Optional[Tuple[int, int]] = None,
    pass_range: Optional[Tuple[int, int]] = None,
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
    device: Optional[str] = None,
    accumulation: Optional[str] = None,
    progress: Optional[Callable[[Progress], None]] = None,
    info: Optional[dict] = None,
    integrator: Optional[str] = None,
    renderer: Optional[RendererCore] = None,
    denoise: Optional[bool] = None,
    aovs: bool = False,
) -> Union[npt.NDArray[np.float32], Dict[str, npt.NDArray[np.float32]]]: ...
def write_image(path: str, image: npt.NDArray[np.float32], exposure: float = 0.0) -> None: ...
def write_layers(path: str, layers: Sequence[Tuple[str, npt.NDArray[np.float32]]]) -> None: ...
def read_image(path: str) -> npt.NDArray[np.float32]: ...
def merge(
    parts: Sequence[str],
    output: Optional[str] = None,
    *,
    accumulation: bool = False,
    layers: bool = False,
    exposure: float = 0.0,
) -> Union[npt.NDArray[np.float32], Dict[str, npt.NDArray[np.float32]]]: ...
def devices() -> List[Dict[str, Union[int, str]]]:
    """The Vulkan devices the loader lists (index, name, type, driver, api_version); empty
    without a Vulkan driver."""
