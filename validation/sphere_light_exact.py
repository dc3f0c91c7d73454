#!/usr/bin/env python3
"""sphere_light_exact.py - the exact image of validation/sphere-light.scene, compared with renders.

A uniformly emitting sphere (radius r, radiance L) entirely above a surface's horizon gives the
irradiance E = pi L (r/d)^2 cos(theta) (d: distance to its centre, theta: from the normal), so a
Lambertian floor of albedo rho has Lo = rho L (r/d)^2 cos(theta). Each pixel is the average over
an N x N midpoint grid of camera rays (pinhole, vertical field of view, top row first).

  usage: sphere_light_exact.py N RENDER.pfm...     (little-endian colour PFMs, 64 x 64)
  e.g.   build/ptv render validation/sphere-light.scene pt.pfm pt-var.pfm 64 64 256 16 pt-regions.txt
         build/pdftrace validation/sphere-light.scene --export-mitsuba mi.xml --size 64x64 --spp 256
         build/mitsuba-venv/bin/python validation/mitsuba_render.py mi.xml mi 16 256
         python3 validation/sphere_light_exact.py 8 pt.pfm mi.pfm
"""
import math
import struct
import sys

W = H = 64
FROM, AT, VFOV = (0.0, 2.0, -4.0), (0.0, 0.0, 3.0), 40.0
RHO, L, CENTRE, R = 0.5, 40000.0, (0.0, 3.0, 2.0), 0.02
FLOOR_HALF = 20.0  # the floor quad spans x, z in [-20, 20] at y = 0


def sub(a, b): return tuple(x - y for x, y in zip(a, b))
def cross(a, b): return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])
def unit(a):
    n = math.sqrt(sum(x * x for x in a))
    return tuple(x / n for x in a)


def exact_image(n):
    """Pixel averages (R only: the scene is grey), top row first."""
    f = unit(sub(AT, FROM))
    right = unit(cross(f, (0.0, 1.0, 0.0)))
    up = cross(right, f)
    t = math.tan(math.radians(VFOV / 2))
    img = []
    for y in range(H):
        for x in range(W):
            s = 0.0
            for j in range(n):
                for i in range(n):
                    px = (x + (i + 0.5) / n) / W * 2 - 1
                    py = 1 - (y + (j + 0.5) / n) / H * 2
                    d = tuple(f[k] + t * (px * right[k] + py * up[k]) for k in range(3))
                    if d[1] >= 0:
                        continue
                    p = tuple(FROM[k] - FROM[1] / d[1] * d[k] for k in range(3))
                    if abs(p[0]) > FLOOR_HALF or abs(p[2]) > FLOOR_HALF:
                        continue
                    v = sub(CENTRE, p)
                    dist = math.sqrt(sum(q * q for q in v))
                    s += RHO * L * R * R * (v[1] / dist) / (dist * dist)
            img.append(s / (n * n))
    return img


def read_pfm_red(path):
    data = open(path, "rb").read()
    parts = data.split(b"\n", 3)
    w, h = map(int, parts[1].split())
    vals = struct.unpack("<%df" % (w * h * 3), parts[3][:w * h * 12])
    return [vals[3 * ((h - 1 - y) * w + x)] for y in range(h) for x in range(w)]


def main(argv):
    if len(argv) < 3:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    exact = exact_image(int(argv[1]))
    half = W * H // 2
    print("exact image mean %.6f" % (sum(exact) / len(exact)))
    for path in argv[2:]:
        m = read_pfm_red(path)
        rel = lambda a, b: 100 * (sum(a) / sum(b) - 1)
        print("%s: %+.3f %% (upper half %+.3f %%, lower half %+.3f %%)" %
              (path, rel(m, exact), rel(m[:half], exact[:half]), rel(m[half:], exact[half:])))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
