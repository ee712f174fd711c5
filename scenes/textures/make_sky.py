"""Writes sky.exr, the latitude-longitude sky of scenes/envmap.toml: a blue
gradient over the upper hemisphere, a dark ground below the horizon and a
small bright sun 35 degrees from the zenith. Needs Mitsuba 3 and NumPy
(`pip install mitsuba numpy`); run from this folder: python3 make_sky.py

Rows go from the zenith (top) to the nadir; columns by azimuth, as rtk's
and Mitsuba's envmap read them (theta = acos(y), phi = atan2(x, -z))."""
import math

import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
W, H = 256, 128
sun_theta, sun_phi, sun_radius = math.radians(35), math.radians(60), math.radians(3)
sun_dir = np.array([math.sin(sun_theta) * math.sin(sun_phi), math.cos(sun_theta),
                    -math.sin(sun_theta) * math.cos(sun_phi)])
img = np.zeros((H, W, 3), dtype=np.float32)
for j in range(H):
    theta = (j + 0.5) / H * math.pi
    for i in range(W):
        phi = (i + 0.5) / W * 2 * math.pi
        d = np.array([math.sin(theta) * math.sin(phi), math.cos(theta),
                      -math.sin(theta) * math.cos(phi)])
        if d[1] >= 0:
            t = d[1]  # 0 at the horizon, 1 at the zenith
            c = (1 - t) * np.array([0.85, 0.9, 1.0]) + t * np.array([0.25, 0.45, 0.9])
        else:
            c = np.array([0.08, 0.07, 0.06])
        if math.acos(min(1.0, float(d @ sun_dir))) < sun_radius:
            c = np.array([400.0, 380.0, 340.0])
        img[j, i] = c
mi.Bitmap(img).write("sky.exr")
