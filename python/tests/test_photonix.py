"""Tests of the installed `photonix` wheel (ci/test installs it into a fresh virtual environment).

Images are tiny and photon counts small: each render takes a fraction of a second on the CPU
backend. PHOTONIX_BIN names the command-line binary the Python renders are compared with
(ci/test sets it to target/release/photonix).
"""

import os
import pathlib
import signal
import subprocess
import threading
import time
import warnings

import numpy as np
import pytest

import photonix

ROOT = pathlib.Path(__file__).resolve().parents[2]
BOX = ROOT / "scenes" / "cornell-box.toml"
# Small and quick, the same for every render below that is compared with another.
SMALL = dict(resolution=(24, 24), photons=3000, caustic_photons=3000, backend="cpu")


def photonix_bin():
    path = os.environ.get("PHOTONIX_BIN") or str(ROOT / "target" / "release" / "photonix")
    if not os.access(path, os.X_OK):
        pytest.skip(f"no photonix binary at {path} (set PHOTONIX_BIN)")
    return path


def test_render_returns_a_float32_height_width_3_array():
    scene = photonix.load(BOX)
    image = photonix.render(scene, passes=1, **dict(SMALL, resolution=(20, 12)))
    assert image.dtype == np.float32 and image.shape == (12, 20, 3)
    assert np.isfinite(image).all() and (image >= 0).all()
    # The Cornell box is lit: mean radiance well above zero in every channel.
    assert (image.mean(axis=(0, 1)) > 0.01).all(), image.mean(axis=(0, 1))


def test_layers_sum_to_the_combined_image():
    layers = photonix.render(BOX, passes=1, layers=True, **SMALL)
    assert set(layers) == {"combined", "direct", "specular", "indirect", "caustics"}
    total = layers["direct"] + layers["specular"] + layers["indirect"] + layers["caustics"]
    # float32 sums of four terms: a few ulps.
    np.testing.assert_allclose(total, layers["combined"], rtol=1e-5, atol=1e-6)


def test_denoise_keeps_the_noisy_image_and_returns_the_feature_layers():
    # Open Image Denoise as the binary finds it (ci/setup installs it into target/oidn).
    info = {}
    layers = photonix.render(BOX, passes=1, denoise=True, aovs=True, info=info, **SMALL)
    assert {"combined", "noisy", "albedo", "normal", "depth", "position"} <= set(layers)
    # The noisy layer is the plain render. The denoised image keeps its mean roughly: at 24x24
    # the light is a handful of pixels whose edges the filter softens (5% seen; the furnace test,
    # tests/denoise.rs, holds 0.5% on a flat image).
    plain = photonix.render(BOX, passes=1, **SMALL)
    np.testing.assert_array_equal(layers["noisy"], plain)
    assert abs(layers["combined"].mean() / plain.mean() - 1) < 0.1
    assert 0 <= layers["albedo"].min() and layers["albedo"].max() <= 1
    assert info["denoise_seconds"] > 0


def test_python_render_writes_the_same_accumulation_file_as_the_command_line(tmp_path):
    binary = photonix_bin()
    ours = tmp_path / "python.exr"
    theirs = tmp_path / "cli.exr"
    photonix.render(BOX, pass_range=(1, 3), seed=7, accumulation=ours, **SMALL)
    subprocess.run(
        [binary, "render", str(BOX), "--pass-range", "1..3", "--seed", "7", "--resolution", "24x24",
         "--photons", "3000", "--caustic-photons", "3000", "--backend", "cpu", "-o", str(theirs)],
        check=True, capture_output=True,
    )
    assert ours.read_bytes() == theirs.read_bytes()


def test_parts_merge_to_the_one_machine_render(tmp_path):
    whole = photonix.render(BOX, passes=3, **SMALL)
    parts = [tmp_path / f"part-{i}.exr" for i in range(3)]
    for i, part in enumerate(parts):
        photonix.render(BOX, pass_range=(i, i + 1), accumulation=part, **SMALL)
    merged = photonix.merge(parts, tmp_path / "merged.exr")
    # One pass per part: the merge adds the passes in the same order the whole render did.
    assert np.array_equal(merged, whole)
    assert np.array_equal(photonix.read_image(tmp_path / "merged.exr"), whole)
    with pytest.raises(photonix.ImageError, match="would count those passes twice"):
        photonix.merge([parts[0], parts[0]])
    other_seed = tmp_path / "seed.exr"
    photonix.render(BOX, pass_range=(5, 6), seed=3, accumulation=other_seed, **SMALL)
    with pytest.raises(photonix.ImageError, match="seed 3 but"):
        photonix.merge([parts[0], other_seed])


def test_setting_a_material_colour_changes_the_image():
    scene = photonix.load(BOX)
    before = photonix.render(scene, passes=1, no_photons=True, **dict(SMALL, photons=None, caustic_photons=None))
    assert scene["materials.red.reflectance"] == [0.63, 0.065, 0.05]
    scene["materials.red.reflectance"] = np.array([0.0, 0.0, 0.9])
    assert scene.get("materials.red.reflectance") == [0.0, 0.0, 0.9]
    after = photonix.render(scene, passes=1, no_photons=True, **dict(SMALL, photons=None, caustic_photons=None))
    # The red wall is the image's left edge (see the scene's comment): red falls, blue rises.
    left_before, left_after = before[:, :4].mean(axis=(0, 1)), after[:, :4].mean(axis=(0, 1))
    assert left_after[0] < 0.2 * left_before[0] and left_after[2] > 2 * left_before[2], (left_before, left_after)


def test_lights_and_camera_are_set_by_path():
    scene = photonix.load(BOX)
    dim = scene.copy()
    dim["lights[ceiling light].radiance"] = [1.7, 1.2, 0.4]
    assert scene["lights[0].radiance"] == [17, 12, 4]
    opts = dict(SMALL, photons=None, caustic_photons=None)
    bright = photonix.render(scene, passes=1, no_photons=True, **opts)
    dark = photonix.render(dim, passes=1, no_photons=True, **opts)
    # Direct light only, linear in the emitted radiance: a tenth.
    np.testing.assert_allclose(dark, bright / 10, rtol=1e-4, atol=1e-7)
    scene["camera.resolution"] = [16, 8]
    assert scene.resolution == (16, 8)
    assert photonix.render(scene, passes=1, no_photons=True, backend="cpu").shape == (8, 16, 3)


def test_a_refused_edit_raises_scene_error_with_file_line_and_changes_nothing():
    scene = photonix.load(BOX)
    text = scene.toml
    with pytest.raises(photonix.SceneError) as error:
        scene["materials.red.reflectance"] = [0.5, 0.5]
    message = str(error.value)
    assert "cornell-box.toml:" in message and "reflectance" in message, message
    assert scene.toml == text
    with pytest.raises(KeyError, match="materials.blue"):
        scene["materials.blue.reflectance"]
    with pytest.raises(KeyError, match=r"\[ceiling light\]"):
        scene["lights[lamp].radiance"] = [1, 1, 1]
    with pytest.raises(ValueError, match="scene path"):
        scene["materials..red"] = 1


def test_scene_text_errors_carry_file_line_and_column():
    with pytest.raises(photonix.SceneError, match=r"^box\.toml:2:\d+: .*colour") as error:
        photonix.loads('[materials.white]\ncolour = [1, 1, 1]\ntype = "diffuse"\n', "box.toml")
    assert "did you mean" in str(error.value) or "unknown field" in str(error.value)
    with pytest.raises(photonix.SceneError, match="nothing.toml"):
        photonix.load("nothing.toml")


def test_bad_options_raise_value_error_before_rendering():
    scene = photonix.load(BOX)
    for options, words in [
        (dict(backend="tpu"), "backend"),
        (dict(passes=0), "passes"),
        (dict(resolution=(0, 4)), "resolution"),
        (dict(passes=2, pass_range=(0, 2)), "pass_range"),
        (dict(no_photons=True, photons=10), "no_photons"),
        (dict(time=-1.0), "time"),
        (dict(accumulation="part.png"), "EXR"),
        (dict(backend="cpu", device="0"), "device"),
    ]:
        with pytest.raises(ValueError, match=words):
            photonix.render(scene, **options)


def test_images_are_written_and_read_back(tmp_path):
    image = np.random.default_rng(1).random((5, 7, 3), dtype=np.float32)
    photonix.write_image(tmp_path / "a.exr", image)
    assert np.array_equal(photonix.read_image(tmp_path / "a.exr"), image)
    photonix.write_image(tmp_path / "a.png", image.astype(np.float64), exposure=1.0)
    assert (tmp_path / "a.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    photonix.write_image(tmp_path / "layers.exr", {"combined": image, "direct": image * 0.5})
    assert (tmp_path / "layers.exr").stat().st_size > 0
    with pytest.raises(ValueError, match="height, width, 3"):
        photonix.write_image(tmp_path / "b.exr", np.zeros((4, 4)))
    with pytest.raises(photonix.ImageError, match="tiff"):
        photonix.write_image(tmp_path / "a.tiff", image)


def test_progress_is_reported_and_a_callback_error_stops_the_render():
    seen = []
    photonix.render(BOX, passes=3, progress=seen.append, **SMALL)
    assert seen and seen[-1].passes_done == 3 and seen[-1].passes_total == 3
    assert all(0.0 <= p.pass_fraction <= 1.0 for p in seen)

    def fail(p):
        raise RuntimeError("stop here")

    with pytest.raises(RuntimeError, match="stop here"):
        photonix.render(BOX, passes=3, progress=fail, **SMALL)


def test_keyboard_interrupt_returns_the_passes_so_far():
    # A real SIGINT, as Ctrl-C sends, once the first pass is done: the render must stop soon
    # after and return the finished passes with a warning.
    info = {}
    done = threading.Event()

    def progress(p):
        if p.passes_done >= 1:
            done.set()

    def interrupt():
        done.wait(60)
        os.kill(os.getpid(), signal.SIGINT)

    # A shell that starts a job in the background without job control (`cmd &` in a script,
    # nohup) leaves SIGINT ignored, and Python then installs no handler: the signal would be
    # dropped and the render run on. Ctrl-C's handler, for this test only.
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    threading.Thread(target=interrupt, daemon=True).start()
    start = time.monotonic()
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            image = photonix.render(BOX, passes=photonix.MAX_PASSES, progress=progress, info=info, **SMALL)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert info["stop_reason"] == "interrupted" and 1 <= info["passes"] < 1000, info
    assert image.shape == (24, 24, 3) and np.isfinite(image).all()
    assert any(issubclass(w.category, RuntimeWarning) and "interrupted" in str(w.message) for w in caught)
    assert time.monotonic() - start < 60


def test_the_render_releases_the_gil():
    count = [0]
    stop = threading.Event()

    def spin():
        while not stop.is_set():
            count[0] += 1

    thread = threading.Thread(target=spin)
    thread.start()
    try:
        before = count[0]
        photonix.render(BOX, passes=2, resolution=(48, 48), photons=20000, caustic_photons=20000, backend="cpu")
        during = count[0] - before
    finally:
        stop.set()
        thread.join()
    # Holding the lock, the render would let the spinning thread run not at all; it does
    # millions of iterations a second when free.
    assert during > 1000, during


def test_adaptive_sampling_leaves_pixels_out_and_is_deterministic():
    # The path-traced box at 32x24 as tests/adaptive.rs renders it: after the warm-up some
    # passes render half of the pixels.
    opts = dict(passes=48, spp=1, integrator="pt", resolution=(32, 24), backend="cpu")
    uniform = photonix.render(BOX, **opts)
    adaptive = photonix.render(BOX, adaptive=True, **opts)
    again = photonix.render(BOX, adaptive=True, **opts)
    assert np.array_equal(adaptive, again)
    assert not np.array_equal(adaptive, uniform)
    ratio = adaptive.mean(axis=(0, 1)) / uniform.mean(axis=(0, 1))
    assert np.all(np.abs(ratio - 1.0) < 0.05), ratio


def test_time_and_target_error_budgets_stop_the_render():
    info = {}
    photonix.render(BOX, time=0.3, info=info, **SMALL)
    assert info["stop_reason"] == "time" and info["passes"] >= 1, info
    info = {}
    photonix.render(BOX, target_error=1000.0, info=info, **SMALL)
    # The estimate needs four passes, and any estimate is below 1000.
    assert info["stop_reason"] == "target_error" and info["passes"] == 4, info


def test_the_gpu_backend_agrees_with_the_cpu_reference():
    if not any(d["type"] for d in photonix.devices()):
        pytest.skip("no Vulkan device")
    options = dict(SMALL, resolution=(16, 16))
    options.pop("backend")
    info = {}
    gpu = photonix.render(BOX, passes=1, backend="gpu", info=info, **options)
    cpu = photonix.render(BOX, passes=1, backend="cpu", **options)
    assert info["backend"] == "gpu"
    # Same random numbers on both: the images agree up to float rounding in the kernels'
    # different summation orders; relMSE far below the noise of one pass.
    rel = np.mean((gpu - cpu) ** 2 / (cpu ** 2 + 1e-2))
    assert rel < 1e-4, rel


def test_the_path_tracer_is_chosen_by_name_and_refuses_photon_options():
    image = photonix.render(BOX, passes=1, integrator="pt", backend="cpu", resolution=(16, 16), spp=4)
    assert image.shape == (16, 16, 3) and (image.mean(axis=(0, 1)) > 0.01).all()
    with pytest.raises(ValueError, match="photons"):
        photonix.render(BOX, passes=1, integrator="pt", photons=1000)
    with pytest.raises(ValueError, match="ppm, pt"):
        photonix.render(BOX, passes=1, integrator="vcmx")


def test_auto_is_the_default_and_photon_options_choose_photon_mapping():
    # cornell-fog has a medium, so auto picks bpt there; photon options ask for ppm instead of
    # being refused, and "auto" can be named too.
    fog = ROOT / "scenes" / "cornell-fog.toml"
    small = dict(passes=1, backend="cpu", resolution=(16, 16), spp=1)
    for options in ({}, {"integrator": "auto"}, {"photons": 1000, "caustic_photons": 1000}):
        image = photonix.render(fog, **small, **options)
        assert image.shape == (16, 16, 3) and np.isfinite(image).all(), options
        assert (image.mean(axis=(0, 1)) > 0.0).all(), options
    with pytest.raises(ValueError, match="photons"):
        photonix.render(fog, integrator="bpt", photons=1000, **small)
