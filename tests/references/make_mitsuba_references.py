#!/usr/bin/env python3
"""Renders the reference scenes of this folder with Mitsuba 3 into mitsuba/<name>.exr.

Each scene is a Photonix scene file (<name>.toml); this script translates the subset they use
(perspective and thin-lens cameras, diffuse, plastic, conductor (given eta and k) and
thin dielectric materials with their microfacet distribution, spheres, an infinite plane, spot lights,
uniform and Hosek-Wilkie sky environments, the box, tent and gaussian filters) into a Mitsuba scene and renders it with the path
tracer. tests/mitsuba_references.rs renders the same files with Photonix and compares.

    pip install mitsuba            # 3.9.1 made the committed files
    apt-get install libllvm19      # for the llvm variant; without it scalar_rgb is used
    python3 tests/references/make_mitsuba_references.py [--spp 4096] [names...]

Conventions bridged here: Mitsuba's sunsky is Z-up in its own frame (turned to Photonix's +y
with to_world), the sun's place follows Photonix's (azimuth clockwise from north, north -z),
and the plane is a rectangle of side 2e4 (Mitsuba has no infinite plane).
"""
import argparse
import math
import os
import sys
import tomllib

HERE = os.path.dirname(os.path.abspath(__file__))


def pick_variant(mi):
    os.environ.setdefault("DRJIT_LIBLLVM_PATH", "libLLVM-19.so")
    for v in ("llvm_ad_rgb", "scalar_rgb"):
        try:
            mi.set_variant(v)
            return v
        except Exception:
            continue
    sys.exit("no usable Mitsuba variant")


def rgb(v):
    if isinstance(v, (int, float)):
        return {"type": "rgb", "value": [float(v)] * 3}
    return {"type": "rgb", "value": [float(x) for x in v]}


def unit(v):
    n = math.sqrt(sum(x * x for x in v))
    return [x / n for x in v]


def sun_direction(elevation_deg, azimuth_deg):
    # As photonix::scene::sky::direction_from_angles with north = -z: east = north x up = +x.
    e, a = math.radians(elevation_deg), math.radians(azimuth_deg)
    north, east = [0.0, 0.0, -1.0], [1.0, 0.0, 0.0]
    return unit([math.cos(e) * (math.cos(a) * n + math.sin(a) * s) + math.sin(e) * u
                 for n, s, u in zip(north, east, [0.0, 1.0, 0.0])])


def translate_material(name, m):
    if m["type"] == "diffuse":
        return {"type": "diffuse", "reflectance": rgb(m.get("reflectance", 0.8))}
    if m["type"] == "plastic":
        # Photonix's outside is vacuum: Mitsuba's default ext_ior is air's 1.000277.
        out = {"int_ior": float(m.get("ior", 1.5)), "ext_ior": 1.0, "nonlinear": bool(m.get("nonlinear", False)),
               "diffuse_reflectance": rgb(m.get("reflectance", 0.8))}
        alpha = float(m.get("roughness", 0.0))
        if alpha == 0.0:
            return {"type": "plastic", **out}
        return {"type": "roughplastic", "distribution": m.get("distribution", "ggx"), "alpha": alpha, **out}
    if m["type"] == "conductor":
        out = {"eta": rgb(m["eta"]), "k": rgb(m["k"]), "specular_reflectance": rgb(m.get("tint", 1.0))}
        alpha = float(m.get("roughness", 0.0))
        if alpha == 0.0:
            return {"type": "conductor", **out}
        return {"type": "roughconductor", "distribution": m.get("distribution", "ggx"), "alpha": alpha, **out}
    if m["type"] == "thin_dielectric":
        return {"type": "thindielectric", "int_ior": float(m.get("ior", 1.5)), "ext_ior": 1.0}
    sys.exit(f"material {name}: type {m['type']} is not translated")


def rfilter(render):
    """The film's filter; `filter_radius` is a tent's radius, a Gaussian's four standard deviations."""
    out = {"type": render.get("filter", "box")}
    if "filter_radius" in render:
        r = float(render["filter_radius"])
        if out["type"] == "tent":
            out["radius"] = r
        elif out["type"] == "gaussian":
            out["stddev"] = r / 4
        else:
            sys.exit("Mitsuba 3's box filter has no radius")
    return out


def translate(mi, scene, spp):
    T = mi.ScalarTransform4f
    cam = scene["camera"]
    w, h = cam["resolution"]
    sensor = {
        "type": "thinlens" if "aperture_radius" in cam else "perspective",
        "fov": float(cam["fov"]),
        "fov_axis": "x",
        "to_world": T().look_at(origin=cam["position"], target=cam["look_at"], up=cam.get("up", [0, 1, 0])),
        "film": {"type": "hdrfilm", "width": w, "height": h, "pixel_format": "rgb",
                 "rfilter": rfilter(scene.get("render", {}))},
        "sampler": {"type": "independent", "sample_count": spp},
    }
    if "aperture_radius" in cam:
        sensor["aperture_radius"] = float(cam["aperture_radius"])
        sensor["focus_distance"] = float(cam["focal_distance"])
    out = {"type": "scene", "integrator": {"type": "path", "max_depth": 32, "rr_depth": 8}, "sensor": sensor}
    bsdfs = {}
    for name, m in scene.get("materials", {}).items():
        bsdfs[name] = translate_material(name, m)
    for k, s in enumerate(scene.get("shapes", [])):
        bsdf = bsdfs[s["material"]]
        if s["type"] == "sphere":
            out[f"shape{k}"] = {"type": "sphere", "center": s["center"], "radius": float(s["radius"]), "bsdf": bsdf}
        elif s["type"] == "plane":
            assert s["normal"] == [0, 1, 0] and "point" not in s, "only the plane y = 0 is translated"
            out[f"shape{k}"] = {"type": "rectangle", "bsdf": bsdf,
                                "to_world": T().rotate([1, 0, 0], -90).scale([1e4, 1e4, 1])}
        else:
            sys.exit(f"shape type {s['type']} is not translated")
    for k, l in enumerate(scene.get("lights", [])):
        assert l["type"] == "spot", "only spot lights are translated"
        out[f"light{k}"] = {"type": "spot", "intensity": rgb(l["intensity"]),
                            "cutoff_angle": float(l["outer_angle"]), "beam_width": float(l["inner_angle"]),
                            "to_world": T().look_at(origin=l["position"], target=l["point_at"], up=[0, 0, 1])}
    env = scene.get("environment")
    if env is not None:
        strength = float(env.get("strength", 1.0))
        if env["type"] == "uniform":
            out["env"] = {"type": "constant", "radiance": rgb(env["radiance"] if strength == 1 else
                                                                 [strength * x for x in env["radiance"]])}
        elif env["type"] == "sky":
            out["env"] = {"type": "sunsky", "turbidity": float(env.get("turbidity", 3.0)),
                          "albedo": rgb(env.get("ground_albedo", 0.3)),
                          "sun_direction": sun_direction(env["sun_elevation"], env["sun_azimuth"]),
                          "sky_scale": strength, "sun_scale": strength if env.get("sun", True) else 0.0,
                          "to_world": T().rotate([1, 0, 0], -90)}
        else:
            sys.exit(f"environment type {env['type']} is not translated")
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--spp", type=int, default=4096)
    ap.add_argument("names", nargs="*")
    args = ap.parse_args()
    import mitsuba as mi
    variant = pick_variant(mi)
    names = args.names or sorted(f[:-5] for f in os.listdir(HERE) if f.endswith(".toml"))
    os.makedirs(os.path.join(HERE, "mitsuba"), exist_ok=True)
    for name in names:
        with open(os.path.join(HERE, name + ".toml"), "rb") as f:
            scene = tomllib.load(f)
        image = mi.render(mi.load_dict(translate(mi, scene, args.spp)))
        path = os.path.join(HERE, "mitsuba", name + ".exr")
        mi.Bitmap(image).write(path)
        print(f"{name}: mitsuba {mi.__version__} {variant}, {args.spp} spp -> {os.path.relpath(path)}")


if __name__ == "__main__":
    main()
