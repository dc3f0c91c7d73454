"""Compares two groups of renders of one scene: per-channel image means and 4x4 region means,
with standard errors from the spread over each group's seeds (independent renders).

  compare.py A1.pfm A2.pfm ... -- B1.exr B2.exr ... [--ref-se-from GROUP]

A group of one image (a stored reference) takes its standard errors from the other group
scaled by sqrt(samples_other / samples_this) given as --one-se-scale F (F = 1: equal samples).
Prints (B - A) / A per channel with z = difference / combined SE, and how many of the 48
region-channel means differ by more than 3 SE.
"""
import sys, math
import mitsuba as mi
mi.set_variant('scalar_rgb')

def load(path):
    b = mi.Bitmap(path).convert(mi.Bitmap.PixelFormat.RGB, mi.Struct.Type.Float32, srgb_gamma=False)
    w, h = b.size()
    t = mi.TensorXf(b)
    flat = list(t.array)
    return w, h, flat

def stats(paths, R=4):
    imgs = [load(p) for p in paths]
    w, h = imgs[0][0], imgs[0][1]
    per = []  # per image: [channel mean], [region][channel] mean
    for (_, _, f) in imgs:
        mean = [0.0] * 3; reg = [[0.0] * 3 for _ in range(R * R)]
        for y in range(h):
            ry = y * R // h
            for x in range(w):
                rx = x * R // w; i = 3 * (y * w + x)
                for c in range(3):
                    v = f[i + c]; mean[c] += v; reg[ry * R + rx][c] += v
        n = w * h; mean = [m / n for m in mean]
        reg = [[v / (n / (R * R)) for v in r] for r in reg]
        per.append((mean, reg))
    k = len(per)
    def ms(vals):
        m = sum(vals) / len(vals)
        se = math.sqrt(sum((v - m) ** 2 for v in vals) / (len(vals) - 1) / len(vals)) if len(vals) > 1 else float('nan')
        return m, se
    mean = [ms([p[0][c] for p in per]) for c in range(3)]
    reg = [[ms([p[1][r][c] for p in per]) for c in range(3)] for r in range(R * R)]
    return k, mean, reg

def main(argv):
    scale = 1.0
    if '--one-se-scale' in argv:
        i = argv.index('--one-se-scale'); scale = float(argv[i + 1]); del argv[i:i + 2]
    j = argv.index('--')
    A, B = argv[:j], argv[j + 1:]
    ka, ma, ra = stats(A); kb, mb, rb = stats(B)
    def fix(x, y):  # a single image borrows the other group's SE
        return [(m, s if not math.isnan(s) else so * scale) for (m, s), (_, so) in zip(x, y)]
    if ka == 1: ma = fix(ma, mb); ra = [fix(a, b) for a, b in zip(ra, rb)]
    if kb == 1: mb = fix(mb, ma); rb = [fix(b, a) for a, b in zip(ra, rb)]
    print(f'A: {ka} image(s) {A[0]} ...; B: {kb} image(s) {B[0]} ...')
    for c, name in enumerate('RGB'):
        (a, sa), (b, sb) = ma[c], mb[c]
        se = math.hypot(sa, sb)
        print(f'  {name}: A {a:.6f}  B {b:.6f}  (B-A)/A {100 * (b - a) / a:+.4f} %  +- {100 * se / a:.4f} %  z {(b - a) / se:+.2f}')
    bad = 0; zs = []
    for r in range(len(ra)):
        for c in range(3):
            (a, sa), (b, sb) = ra[r][c], rb[r][c]
            z = (b - a) / math.hypot(sa, sb); zs.append(z); bad += abs(z) > 3
    print(f'  4x4 regions x 3 channels: {bad} of {len(zs)} beyond 3 SE; mean z {sum(zs) / len(zs):+.2f}, '
          f'max |z| {max(abs(z) for z in zs):.2f}')
    print('  region (B-A)/A in % (green), rows top to bottom:')
    for y in range(4):
        print('   ' + ' '.join(f'{100 * (rb[4 * y + x][1][0] - ra[4 * y + x][1][0]) / ra[4 * y + x][1][0]:+.3f}' for x in range(4)))

if __name__ == '__main__':
    main(sys.argv[1:])
