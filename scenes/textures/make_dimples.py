"""Writes dimples.png, the height field of the bumped ball in
scenes/materials.toml: a grid of round dimples, 8-bit grey, to be read
with raw = true. Needs Mitsuba 3 and NumPy; run from this folder."""
import mitsuba as mi
import numpy as np

mi.set_variant("scalar_rgb")
N = 128
y, x = np.mgrid[0:N, 0:N] / N
# Distance to the nearest cell centre of an 8 x 8 grid, in cell units.
d = np.hypot((x * 8) % 1 - 0.5, (y * 8) % 1 - 0.5)
h = np.clip(1.0 - (0.45 - np.minimum(d, 0.45)) ** 2 / 0.45**2, 0, 1)
mi.Bitmap((h * 255).astype(np.uint8).reshape(N, N, 1), mi.Bitmap.PixelFormat.Y).write("dimples.png")
