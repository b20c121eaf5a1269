"""The scene API a Mitsuba 3 user looks for (`load` of every front-end's files, `load_dict`,
`traverse`, adding and removing entries) and the kept `Renderer` (set-up once, cancel from
another thread, edits while it renders). Tiny images, few photons: each render is a fraction of
a second on the CPU backend; the kept-renderer timing runs on lavapipe (the GPU backend)."""

import os
import pathlib
import subprocess
import threading
import time

import numpy as np
import pytest

import photonix

ROOT = pathlib.Path(__file__).resolve().parents[2]
BOX = ROOT / "scenes" / "cornell-box.toml"
OPTS = dict(resolution=(16, 16), photons=2000, caustic_photons=2000)
SMALL = dict(OPTS, backend="cpu")
CLI_SMALL = ["--resolution", "16x16", "--photons", "2000", "--caustic-photons", "2000", "--backend", "cpu"]


def photonix_bin():
    path = os.environ.get("PHOTONIX_BIN") or str(ROOT / "target" / "release" / "photonix")
    if not os.access(path, os.X_OK):
        pytest.skip(f"no photonix binary at {path} (set PHOTONIX_BIN)")
    return path


# --- load: every front-end ---------------------------------------------------------------------

@pytest.mark.parametrize(
    "source",
    ["docs/pov/first-round.pov", "scenes/meshes/rounded-cube.glb", "tests/mitsuba/conventions.xml"],
)
def test_load_reads_pov_gltf_and_mitsuba_as_the_command_line_does(source, tmp_path):
    """A POV-Ray, glTF or Mitsuba file loads through the command line's front-end and renders the
    same accumulation file, byte for byte, as `photonix render FILE` (same flags)."""
    path = ROOT / source
    scene = photonix.load(path)
    assert scene.source == path and scene.path == path.with_suffix(".toml"), (scene.source, scene.path)
    assert "[camera]" in scene.toml and scene.get("camera.resolution")
    ours, theirs = tmp_path / "python.exr", tmp_path / "cli.exr"
    photonix.render(scene, pass_range=(0, 1), accumulation=ours, **SMALL)
    subprocess.run(
        [photonix_bin(), "render", str(path), "--pass-range", "0..1", "-o", str(theirs), *CLI_SMALL],
        check=True, capture_output=True,
    )
    assert ours.read_bytes() == theirs.read_bytes(), f"{source}: Python and the command line differ"
    # Edited like any scene: the translated TOML is the text that renders.
    params = photonix.traverse(scene)
    assert "camera.position" in params and params.type("camera.position").startswith("list[")


def test_load_sizes_a_pov_scene_and_refuses_a_size_for_toml():
    scene = photonix.load(ROOT / "docs/pov/first-round.pov", resolution=(64, 48))
    assert scene.resolution == (64, 48)
    with pytest.raises(ValueError, match="resolution"):
        photonix.load(BOX, resolution=(64, 48))
    with pytest.raises(photonix.SceneError, match="nothing.pov"):
        photonix.load(ROOT / "nothing.pov")


# --- load_dict -----------------------------------------------------------------------------------

def test_load_dict_of_a_scene_renders_as_the_scene():
    scene = photonix.load(BOX)
    again = photonix.load_dict(scene.to_dict(), path=BOX)
    a = photonix.render(scene, passes=1, **SMALL)
    b = photonix.render(again, passes=1, **SMALL)
    assert np.array_equal(a, b)


def test_load_dict_builds_a_scene_from_python_values():
    scene = photonix.load_dict({
        "camera": {"position": [0, 1, 4], "look_at": [0, 1, 0], "fov": 40, "resolution": [16, 16]},
        "materials": {"white": {"type": "diffuse", "reflectance": np.array([0.8, 0.8, 0.8])}},
        "shapes": [
            {"name": "ball", "type": "sphere", "center": [0, 1, 0], "radius": 1, "material": "white"},
            {"name": "floor", "type": "quad", "material": "white",
             "vertices": [[-5, 0, -5], [5, 0, -5], [5, 0, 5], [-5, 0, 5]]},
        ],
        "lights": [{"type": "point", "position": [0, 3, 2], "intensity": [20, 20, 20]}],
    })
    assert "[[shapes]]" in scene.toml and "[materials.white]" in scene.toml
    image = photonix.render(scene, passes=1, spp=1, backend="cpu")
    assert image.shape == (16, 16, 3) and image.mean() > 0.01
    with pytest.raises(photonix.SceneError, match="colour|unknown field"):
        photonix.load_dict({"camera": {"position": [0, 1, 4], "look_at": [0, 1, 0], "colour": 1}})


# --- traverse, add, remove -----------------------------------------------------------------------

def test_traverse_lists_every_path_with_its_value_and_type_and_updates_in_place():
    scene = photonix.load(BOX)
    params = photonix.traverse(scene)
    assert params["materials.red.reflectance"] == [0.63, 0.065, 0.05]
    assert params.type("materials.red.reflectance") == "list[float]"
    assert params["shapes[floor].material"] == "white" and params.type("shapes[floor].material") == "str"
    assert params.type("render.spp") == "int" and params.type("camera.fov") == "float"
    # Every leaf of the scene, and each path reads back through Scene.get.
    assert len(params) > 40
    for path in params:
        assert scene.get(path) == params[path], path
    print(repr(params).splitlines()[:6])
    before = photonix.render(scene, passes=1, **SMALL)
    params["materials.red.reflectance"] = [0.1, 0.1, 0.9]
    params["render.seed"] = 3
    assert sorted(params.update()) == ["materials.red.reflectance", "render.seed"]
    assert scene["materials.red.reflectance"] == [0.1, 0.1, 0.9] and scene["render.seed"] == 3
    assert not np.array_equal(before, photonix.render(scene, passes=1, **SMALL))
    # All or nothing: one refused value leaves every staged change out.
    params["camera.fov"] = 10.0
    params["materials.red.type"] = "velvet"
    with pytest.raises(photonix.SceneError, match="velvet"):
        params.update()
    assert scene["camera.fov"] != 10.0
    with pytest.raises(KeyError):
        params["materials.red.colour"] = 1


def test_add_and_remove_shapes_lights_and_materials():
    scene = photonix.load(BOX)
    shapes = len(scene["shapes"])
    scene.add("materials.blue", {"type": "diffuse", "reflectance": [0.1, 0.1, 0.8]})
    scene.add("shapes", {"name": "ball", "type": "sphere", "center": [278, 100, 280], "radius": 80,
                         "material": "blue"})
    scene.add("lights", {"type": "point", "position": [278, 400, 280], "intensity": [1e4, 1e4, 1e4]})
    assert len(scene["shapes"]) == shapes + 1 and scene["shapes[ball].material"] == "blue"
    assert "[materials.blue]" in scene.toml
    with pytest.raises(ValueError, match="there already"):
        scene.add("materials.blue", {"type": "diffuse"})
    # A material still in use cannot go; the scene is unchanged.
    with pytest.raises(photonix.SceneError, match="blue"):
        scene.remove("materials.blue")
    scene.remove("shapes[ball]")
    scene.remove("materials.blue")
    scene.remove("lights[1]")
    assert len(scene["shapes"]) == shapes and "blue" not in scene.toml
    with pytest.raises(KeyError, match="no such entry"):
        scene.remove("shapes[ball]")
    # Back to the file's scene: the same image.
    assert np.array_equal(photonix.render(scene, passes=1, **SMALL),
                          photonix.render(photonix.load(BOX), passes=1, **SMALL))


# --- info, the kept renderer, cancel ---------------------------------------------------------------

def test_info_says_which_integrator_auto_chose():
    info = {}
    photonix.render(BOX, passes=1, resolution=(8, 8), backend="cpu", info=info)
    assert info["integrator"] == "ppm" and info["integrator_reason"].startswith("auto:"), info
    info = {}
    photonix.render(BOX, passes=1, resolution=(8, 8), backend="cpu", integrator="pt", info=info)
    assert info["integrator"] == "pt" and info["integrator_reason"] is None, info


def test_a_kept_renderer_skips_the_set_up_on_its_second_render():
    """On lavapipe at 16x16: the first render opens the device and makes the kernels, the
    second reuses them; both render what a one-off render does."""
    if not photonix.devices():
        pytest.skip("no Vulkan device (lavapipe)")
    scene = photonix.load(BOX)
    options = dict(passes=1, resolution=(16, 16), photons=2000, caustic_photons=2000)
    with photonix.Renderer(scene, backend="gpu") as renderer:
        first, second = {}, {}
        t = time.perf_counter()
        a = renderer.render(info=first, **options)
        first_wall = time.perf_counter() - t
        t = time.perf_counter()
        b = renderer.render(info=second, **options)
        second_wall = time.perf_counter() - t
        scene["materials.red.reflectance"] = [0.2, 0.2, 0.8]
        edited = {}
        c = renderer.render(info=edited, **options)
    print(f"kept renderer on {first['device']}: first call {first_wall:.2f} s (set-up "
          f"{first['setup_seconds']:.2f} s), second {second_wall:.2f} s (set-up "
          f"{second['setup_seconds']:.3f} s), after an edit set-up {edited['setup_seconds']:.3f} s")
    assert not first["renderer_kept"] and second["renderer_kept"] and edited["renderer_kept"]
    assert second["setup_seconds"] < first["setup_seconds"] / 5, (first, second)
    assert np.array_equal(a, b)
    assert np.array_equal(a, photonix.render(photonix.load(BOX), backend="gpu", **options))
    assert np.array_equal(c, photonix.render(scene, backend="gpu", **options))
    with pytest.raises(photonix.RenderError, match="closed"):
        renderer.render(**options)


def render_in_a_thread(renderer, **options):
    """Starts renderer.render(**options) on another thread; returns the thread, the result
    holder and an event set once a pass has finished."""
    result, progressed = {}, threading.Event()

    def progress(p):
        if p.passes_done >= 1:
            progressed.set()

    def run():
        try:
            result["image"] = renderer.render(progress=progress, info=result.setdefault("info", {}), **options)
        except BaseException as e:  # noqa: BLE001: handed to the test's thread
            result["error"] = e

    thread = threading.Thread(target=run)
    thread.start()
    return thread, result, progressed


def test_cancel_stops_a_render_on_another_thread_and_returns_its_passes():
    scene = photonix.load(BOX)
    renderer = photonix.Renderer(scene, backend="cpu")
    thread, result, progressed = render_in_a_thread(renderer, passes=100000, **OPTS)
    assert progressed.wait(60), "no pass finished"
    renderer.cancel()
    thread.join(30)
    assert not thread.is_alive(), "cancel did not stop the render"
    assert "error" not in result, result.get("error")
    info = result["info"]
    assert info["stop_reason"] == "cancelled" and 1 <= info["passes"] < 100000, info
    assert result["image"].shape == (16, 16, 3)
    # The renderer renders again after a cancel; a cancel with nothing under way does nothing.
    renderer.cancel()
    assert renderer.render(passes=1, resolution=(8, 8)).shape == (8, 8, 3)
    renderer.close()


def test_editing_a_scene_while_another_thread_renders_it_is_safe():
    scene = photonix.load(BOX)
    renderer = photonix.Renderer(scene, backend="cpu")
    thread, result, progressed = render_in_a_thread(renderer, passes=100000, **OPTS)
    assert progressed.wait(60), "no pass finished"
    # No "Already borrowed": the render goes on with the scene as it was when it started.
    for r in (0.1, 0.5, 0.9):
        scene["materials.red.reflectance"] = [r, 0.1, 0.1]
        photonix.traverse(scene)
    scene.add("materials.blue", {"type": "diffuse", "reflectance": [0.1, 0.1, 0.8]})
    renderer.cancel()
    thread.join(30)
    assert "error" not in result, result.get("error")
    assert scene["materials.red.reflectance"] == [0.9, 0.1, 0.1]
    renderer.close()
