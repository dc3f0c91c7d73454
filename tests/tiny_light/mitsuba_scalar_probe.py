"""Mitsuba 3 scalar_rgb: the sphere light density at 20000 float points 3 .. 4 from a sphere of
radius 0.02, against 1 / (2 pi (1 - cos)) in double; prints the mean ratio - 1 and the
2^-26 / (1 - cos) prediction (docs/accuracy.md, "Tiny sphere lights and Mitsuba")."""
import math, random, mitsuba as mi
mi.set_variant('scalar_rgb')
r = 0.02; C = [1.4, 3.0, 2.6]
scene = mi.load_dict({'type': 'scene', 'bulb': {'type': 'sphere', 'center': C, 'radius': r,
    'emitter': {'type': 'area', 'radiance': {'type': 'rgb', 'value': [1.0, 1.0, 1.0]}}}})
em = scene.emitters()[0]
random.seed(3); acc = 0.0; n = 20000; pred = 0.0
import struct
f32 = lambda x: struct.unpack('f', struct.pack('f', x))[0]
for i in range(n):
    d = random.uniform(3, 4); z = random.uniform(-1, 1); ph = random.uniform(0, 2 * math.pi); s = math.sqrt(1 - z * z)
    p = [f32(C[0] + d * s * math.cos(ph)), f32(C[1] + d * s * math.sin(ph)), f32(C[2] + d * z)]
    it = mi.Interaction3f(); it.p = mi.Point3f(*p)
    ds, w = em.sample_direction(it, mi.Point2f(random.random(), random.random()))
    d2 = sum((f32(C[k]) - p[k]) ** 2 for k in range(3)); s2 = r * r / d2; omc = s2 / (1 + math.sqrt(1 - s2))
    acc += (1 / (2 * math.pi * omc)) / float(ds.pdf) - 1; pred += 2 ** -26 / omc
print(f'scalar_rgb, d in [3,4): mean(pdf_exact/pdf_mitsuba) - 1 = {acc / n:+.3e}, prediction {pred / n:.3e}')
