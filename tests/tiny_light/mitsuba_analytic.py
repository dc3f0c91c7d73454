"""Mitsuba 3 against the closed form for a tiny sphere light (docs/accuracy.md, "Tiny sphere
lights and Mitsuba"): a Lambertian plane y = 0 (albedo rho) under a sphere of radius r and
radiance L at height h. Wholly above the plane's horizon, the sphere gives E = pi L sin^2(alpha)
cos(theta) = pi L r^2 cos(theta) / d^2, so the plane's radiance is rho L r^2 cos(theta) / d^2.

For N points on the plane (float32, as Mitsuba sees them) it compares, in double:
  - the density Mitsuba's sphere returns with a light sample, and its pdf_direction, with
    1 / (2 pi (1 - cos theta_max)), 1 - cos theta_max = s^2 / (1 + sqrt(1 - s^2)), s = r / d;
  - Mitsuba's next-event estimate (scene.sample_emitter_direction, visibility tested) of the
    plane's radiance, rho / pi * weight * cos, with the closed form;
  - a whole render (path tracer, max_depth 2 = direct light only, box filter) with the closed
    form integrated over the same camera rays' hit points.
  mitsuba_analytic.py [--radius R] [--height H] [--n N]
"""
import argparse, math
import mitsuba as mi, drjit as dr

ap = argparse.ArgumentParser()
ap.add_argument('--radius', type=float, default=0.02); ap.add_argument('--height', type=float, default=3.0)
ap.add_argument('--n', type=int, default=1 << 22); ap.add_argument('--spp', type=int, default=256)
args = ap.parse_args()
mi.set_variant('llvm_ad_rgb')
from drjit.llvm.ad import Float64

r, h, rho = args.radius, args.height, 0.5
L = 1.0 / (r * r)            # plane radiance rho cos / d^2: O(0.05) under the light
C = [0.11, h, -0.07]
scene = mi.load_dict({'type': 'scene',
    'integrator': {'type': 'path', 'max_depth': 2},
    'sensor': {'type': 'perspective', 'fov_axis': 'y', 'fov': 70.0,
               'to_world': mi.ScalarTransform4f().look_at(origin=[0, 1, 0], target=[0, 0, 0], up=[0, 0, -1]),
               'sampler': {'type': 'independent'},
               'film': {'type': 'hdrfilm', 'width': 64, 'height': 64, 'rfilter': {'type': 'box'}, 'pixel_format': 'rgb'}},
    'plane': {'type': 'rectangle', 'to_world': mi.ScalarTransform4f().rotate([1, 0, 0], -90).scale(20),
              'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [rho] * 3}}},
    'bulb': {'type': 'sphere', 'center': C, 'radius': r,
             'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [0, 0, 0]}},
             'emitter': {'type': 'area', 'radiance': {'type': 'rgb', 'value': [L] * 3}}}})

def exact_radiance(p):
    dx = Float64(mi.Float(C[0])) - Float64(p.x); dy = Float64(mi.Float(C[1])) - Float64(p.y)
    dz = Float64(mi.Float(C[2])) - Float64(p.z)
    d2 = dx * dx + dy * dy + dz * dz
    s2 = (r * r) / d2
    return rho * L * s2 * dy / dr.sqrt(d2), s2   # rho L r^2 cos / d^2 (normal +y)

N = args.n
rng = mi.PCG32(size=N, initstate=11)
# points on the plane within 2.5 h of the foot of the light (theta + alpha < pi/2 everywhere)
p = mi.Point3f(C[0] + 5 * h * (rng.next_float32() - 0.5), 0.0, C[2] + 5 * h * (rng.next_float32() - 0.5))
ray = mi.Ray3f(mi.Point3f(p.x, 1.0, p.z), mi.Vector3f(0, -1, 0))
si = scene.ray_intersect(ray)
want, s2 = exact_radiance(si.p)
omc = s2 / (1 + dr.sqrt(1 - s2))
ds, w = scene.sample_emitter_direction(si, mi.Point2f(rng.next_float32(), rng.next_float32()), True)
pdf = Float64(ds.pdf)
est = rho / math.pi * Float64(w.x) * Float64(dr.maximum(0, ds.d.y))
pdf_dir = Float64(scene.pdf_emitter_direction(si, ds))
sel = dr.isfinite(want) & (want > 0)
n = int(dr.count(sel)[0])
mean = lambda x: (dr.sum(dr.select(sel, x, 0)) / n)[0]
rel = est / want - 1
mr = mean(rel); se = math.sqrt(mean((rel - mr) ** 2) / n)
print(f'Mitsuba {mi.__version__} {mi.variant()}: sphere r = {r} at height {h}, {n} points on the plane, '
      f'sin^2(theta_max) {dr.min(dr.select(sel, s2, 1))[0]:.2e} .. {dr.max(dr.select(sel, s2, 0))[0]:.2e}')
print(f'  light-sample density / exact - 1:    mean {mean(pdf * 2 * math.pi * omc - 1):+.3e}')
print(f'  pdf_direction / exact - 1:           mean {mean(pdf_dir * 2 * math.pi * omc - 1):+.3e}')
print(f'  predicted by rounding, -2^-26/(1 - cos theta_max): mean {-mean(2.0 ** -26 / omc):+.3e}')
print(f'  next-event estimate / exact - 1:     {mr:+.3e} +- {se:.1e} (z {mr / se:+.1f})')

# a whole render against the closed form over the same camera rays
img = mi.render(scene, spp=args.spp, seed=3)
sensor = scene.sensors()[0]
M = 64 * 64 * 64
rs = mi.PCG32(size=M, initstate=5)
cray, _ = sensor.sample_ray(0.0, 0.5, mi.Point2f(rs.next_float32(), rs.next_float32()), mi.Point2f(0.5, 0.5))
csi = scene.ray_intersect(cray)
cw, _ = exact_radiance(csi.p)
ref = (dr.sum(cw) / M)[0]
ref_se = math.sqrt((dr.sum((cw - ref) ** 2) / M)[0] / M)
t = img.array; g = t[1::3]
m = (dr.sum(Float64(g)) / (64 * 64))[0]
print(f'  render ({args.spp} spp, path max_depth 2): image mean {m:.7f}, closed form over the film {ref:.7f} '
      f'+- {ref_se:.1e}: {100 * (m / ref - 1):+.4f} %')
