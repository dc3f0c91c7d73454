"""Hand-written Mitsuba 3 twin of bench/scenes/tiny-light-pure.scene (and tiny-light.scene with
--window), for the tiny-light investigation (docs/accuracy.md, "Tiny sphere lights and Mitsuba").

  twin.py OUT.exr --spp N --seed S [--window] [--point] [--max-depth N] [--size W]

--point replaces the bulb (a sphere of radius r and radiance L) by a point light of intensity
pi r^2 L at its centre: a sphere wholly above a receiver's horizon gives exactly the irradiance of
that point (E = pi L sin^2(alpha) cos(theta) = pi r^2 L cos(theta) / d^2), so the two differ only
in the penumbrae (a tiny sphere's soft shadow edges against sharp ones) and in the bulb's own
reflection of light, O(r^2/d^2). Conventions: /work/shared/docs/mitsuba-facts.md, docs/mitsuba.md.
"""
import argparse, math, time
import mitsuba as mi

def rect(q, u, v, bsdf):
    # pdftrace's quad Q + a u + b v, a, b in [0, 1] -> Mitsuba's [-1, 1]^2 rectangle
    n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]]
    ln = math.sqrt(sum(x * x for x in n)); n = [x / ln for x in n]
    c = [q[i] + u[i] / 2 + v[i] / 2 for i in range(3)]
    m = [[u[i] / 2, v[i] / 2, n[i], c[i]] for i in range(3)] + [[0, 0, 0, 1]]
    return {'type': 'rectangle', 'to_world': mi.ScalarTransform4f(m), 'bsdf': bsdf}

def lambert(rgb):
    return {'type': 'twosided', 'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': rgb}}}

def scene_dict(args):
    floor = lambert([0.7, 0.7, 0.7]); wall = lambert([0.65, 0.62, 0.55])
    red = lambert([0.65, 0.2, 0.12]); blue = lambert([0.15, 0.3, 0.6])
    L = [40000.0, 36000.0, 30000.0]; r = 0.02; c = [1.4, 3.0, 2.6]
    d = {'type': 'scene',
         'integrator': {'type': 'path', 'max_depth': args.max_depth + 1},
         'sensor': {'type': 'perspective', 'fov_axis': 'y', 'fov': 44.0,
                    'to_world': mi.ScalarTransform4f().look_at(origin=[0.8, 2.0, -4.4], target=[-0.6, 0.5, 1.2], up=[0, 1, 0]),
                    'sampler': {'type': 'independent', 'sample_count': args.spp},
                    'film': {'type': 'hdrfilm', 'width': args.size, 'height': args.size, 'rfilter': {'type': 'box'},
                             'pixel_format': 'rgb', 'component_format': 'float32'}},
         'floor': rect([-3, 0, -6], [0, 0, 10], [6, 0, 0], floor),
         'back': rect([-3, 0, 4], [6, 0, 0], [0, 3.2, 0], wall),
         'left': rect([-3, 0, -6], [0, 3.2, 0], [0, 0, 10], wall),
         'box': {'type': 'cube', 'to_world': mi.ScalarTransform4f().translate([0.3, 0.5, 1.1]).scale([0.5, 0.5, 0.5]), 'bsdf': blue},
         'ball': {'type': 'sphere', 'center': [-1.2, 0.5, 1.8], 'radius': 0.5, 'bsdf': red}}
    if args.point:
        d['bulb'] = {'type': 'point', 'position': c, 'intensity': {'type': 'rgb', 'value': [math.pi * r * r * x for x in L]}}
    else:
        d['bulb'] = {'type': 'sphere', 'center': c, 'radius': r,
                     'bsdf': {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [0, 0, 0]}},
                     'emitter': {'type': 'area', 'radiance': {'type': 'rgb', 'value': L}}}
    if args.window:
        # quad -2.99 0.3 -1.5  0 2 0  0 0 4: u x v = +x, one-sided, shining into the room
        w = rect([-2.99, 0.3, -1.5], [0, 2, 0], [0, 0, 4], {'type': 'diffuse', 'reflectance': {'type': 'rgb', 'value': [0, 0, 0]}})
        w['emitter'] = {'type': 'area', 'radiance': {'type': 'rgb', 'value': [2.2, 2.5, 3.0]}}
        d['window'] = w
    return d

def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('out'); ap.add_argument('--spp', type=int, default=64); ap.add_argument('--seed', type=int, default=0)
    ap.add_argument('--window', action='store_true'); ap.add_argument('--point', action='store_true')
    ap.add_argument('--max-depth', type=int, default=50); ap.add_argument('--size', type=int, default=128)
    ap.add_argument('--variant', default='llvm_ad_rgb')
    args = ap.parse_args()
    mi.set_variant(args.variant)
    import drjit as dr
    scene = mi.load_dict(scene_dict(args))
    t0 = time.time()
    img = mi.render(scene, spp=args.spp, seed=args.seed)
    dr.eval(img)
    mi.Bitmap(img).write(args.out)
    print(f'{args.out}: {args.spp} spp seed {args.seed} in {time.time() - t0:.1f} s')

if __name__ == '__main__':
    main()
