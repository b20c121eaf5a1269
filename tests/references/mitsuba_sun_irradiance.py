#!/usr/bin/env python3
"""Prints the sun's irradiance (linear sRGB, on a plane facing it) of Mitsuba 3's `sunsky` in its
spectral mode, for the cases of the unit test `the_sun_matches_mitsubas_spectral_sunsky`
(src/scene/sky/mod.rs): the spectral radiance at the disc's centre (uniform without
`complex_sun`) at every nanometre of 360..830, integrated against the CIE 1931 table, divided by
the integral of y-bar, turned into linear sRGB and multiplied by the disc's solid angle.

    pip install mitsuba            # 3.9.1 gave the figures in the test
    python3 tests/references/mitsuba_sun_irradiance.py
"""
import math

import mitsuba as mi

mi.set_variant("scalar_spectral")
SUN_HALF_ANGLE = math.radians(0.5358 / 2)
SOLID_ANGLE = 2 * math.pi * (1 - math.cos(SUN_HALF_ANGLE))
CIE_Y_INTEGRAL = 106.856895

for turbidity, elevation in [(3.0, 30.0), (3.0, 60.0), (2.5, 40.0)]:
    e = math.radians(elevation)
    sun = [math.cos(e), 0.0, math.sin(e)]  # Mitsuba's sunsky is Z-up
    emitter = mi.load_dict({"type": "sunsky", "turbidity": turbidity, "albedo": 0.3,
                            "sun_direction": sun, "sky_scale": 0.0})
    xyz = [0.0, 0.0, 0.0]
    for nm in range(360, 831):
        si = mi.SurfaceInteraction3f()
        si.wi = [-c for c in sun]
        si.wavelengths = [nm] * 4
        radiance = emitter.eval(si)[0]
        bar = mi.cie1931_xyz(nm)
        for k in range(3):
            xyz[k] += radiance * bar[k] / CIE_Y_INTEGRAL
    x, y, z = xyz
    rgb = [3.2404542 * x - 1.5371385 * y - 0.4985314 * z,
           -0.9692660 * x + 1.8760108 * y + 0.0415560 * z,
           0.0556434 * x - 0.2040259 * y + 1.0572252 * z]
    print(f"turbidity {turbidity}, elevation {elevation}: [{', '.join(f'{c * SOLID_ANGLE:.6f}' for c in rgb)}]")
