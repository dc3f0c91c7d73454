"""mitsuba_series.py - Mitsuba 3 on the benchmark's error-against-time axes (bench/bench.c runs it).

  python mitsuba_series.py check
      exit 0 when mitsuba and its llvm_ad_rgb variant load, else 1 with the reason on stderr.
  python mitsuba_series.py series --xml SCENE.xml --ref REF.pfm --floor F --budget S --seeds N
                                  [--samplers independent,multijitter] [--max-spp M] [--out FILE.tsv]
      for each sampler a ladder of renders at 1, 2, 4, ... spp: the first seed renders until one render
      takes at least S seconds, until its raw relMSE comes within 10x the reference's noise floor F, or
      up to M spp; seeds 2..N render the same ladder. Seeds are interleaved (seed-major, as bench.c's
      runs). One line per render: sampler, seed, spp asked, spp used, seconds, relMSE, bias.
  python mitsuba_series.py refcheck --xml SCENE.xml --ref REF.pfm [REF2.pfm ...] --spp N --seeds K [--ref-spp R]
      K independent renders of N spp (seeds B+1 .. B+K, --seed-base B, default 1000) against stored
      references: the mean per channel and the means of 4x4 regions, each with its standard error over
      the K seeds, and z = (Mitsuba - reference) / SE; z_both also counts the reference's own noise.
  python mitsuba_series.py serve
      renders on request (commands on standard input, one answer a line): bench.c's throughput part,
      which interleaves these renders with pdftrace's (see cmd_serve).

Variant llvm_ad_rgb (SIMD wavefronts on every core). Time is the render alone: mi.render with the
evaluation of the image forced inside the timed region (drjit.eval, then drjit.sync_thread waits for
the kernels), after one untimed warm-up render of the same sampler and sample count (Dr.Jit compiles
a kernel per configuration on first use; the timed renders then find it compiled) while the renders
are short enough for the compile to matter (WARMUP_BELOW). Scene loading is
not timed, as bench.c does not time pdftrace's scene build.

relMSE and bias are bench.c's definitions (its measure()): over all pixels p and channels c,
relMSE = mean (x - r)^2 / (r^2 + 0.01) and bias = sum x / sum r - 1, x the render, r the reference;
reported raw (bench.c subtracts the floor). The sampler named in the XML is replaced by the one
measured; its sample count is set by mi.render's spp (multijitter may round it up: the count used is
reported). """
import argparse
import array
import math
import os
import re
import sys
import time

VARIANT = "llvm_ad_rgb"
FLOOR_STOP = 10.0  # as bench.c: a series stops when raw relMSE < 10 x the reference's noise floor
WARMUP_SEED = 0x5EED + 1  # not a timed seed (those are 1..N)
# A warm-up render only while the previous level took less than this many seconds: a kernel
# compiles in 0.2-0.4 s here (measured at 128x128: 0.27 s for a first render of 3 spp against
# 0.055 s warm), under 1 % of a render twice as long as this.
WARMUP_BELOW = 20.0


def load_mitsuba():
    """Imports mitsuba and drjit and selects the variant; raises ImportError / other with the reason."""
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(VARIANT)
    mi.set_log_level(mi.LogLevel.Error)  # multijitter's "sample count rounded up" notes: the TSV has the count
    return mi, dr


def read_pfm(path):
    """A colour PFM as (width, height, floats top row first, RGB interleaved)."""
    with open(path, "rb") as f:
        data = f.read()
    # header: "PF", width, height, scale (negative: little-endian), each followed by white space
    m = re.match(rb"PF\s+(\d+)\s+(\d+)\s+(-?[0-9.eE+-]+)\s", data)
    if not m:
        raise ValueError("%s: not a colour PFM" % path)
    w, h, scale = int(m.group(1)), int(m.group(2)), float(m.group(3))
    px = array.array("f")
    px.frombytes(data[m.end():m.end() + 12 * w * h])
    if len(px) != 3 * w * h:
        raise ValueError("%s: truncated" % path)
    if (scale < 0) != (sys.byteorder == "little"):
        px.byteswap()
    rows = [px[3 * w * y:3 * w * (y + 1)] for y in range(h)]
    rows.reverse()  # PFM stores the bottom row first
    out = array.array("f")
    for r in rows:
        out.extend(r)
    return w, h, out


def image_floats(dr, img):
    """The rendered tensor (height, width, channels) as RGB floats, top row first."""
    shape = tuple(img.shape)
    if len(shape) != 3 or shape[2] < 3:
        raise ValueError("unexpected image shape %s (the film must be RGB)" % (shape,))
    flat = list(img.array)
    h, w, ch = shape
    if ch == 3:
        return w, h, flat
    return w, h, [flat[ch * i + c] for i in range(w * h) for c in range(3)]


def write_pfm(path, w, h, px):
    """Writes RGB floats (top row first) as a little-endian PFM (bottom row first)."""
    a = array.array("f", px)
    if sys.byteorder != "little":
        a.byteswap()
    b = a.tobytes()
    with open(path, "wb") as f:
        f.write(b"PF\n%d %d\n-1\n" % (w, h))
        for y in range(h - 1, -1, -1):
            f.write(b[12 * w * y:12 * w * (y + 1)])


def measure(x, r):
    """bench.c's relMSE and bias of x against r (flat float sequences of equal length)."""
    mse = sx = sr = 0.0
    for xv, rv in zip(x, r):
        d = xv - rv
        mse += d * d / (rv * rv + 0.01)
        sx += xv
        sr += rv
    return mse / len(x), (sx / sr - 1.0 if sr > 0 else 0.0)


def load_scene(mi, xml_path, sampler, max_depth=0, rr_depth=0):
    """The scene of xml_path with its sampler replaced by `sampler` (file paths resolve beside it) and,
    when > 0, the path integrator's max_depth (Mitsuba's count: segments) and rr_depth set."""
    with open(xml_path) as f:
        text = set_depth(f.read(), max_depth, rr_depth)
    text, n = re.subn(r'<sampler\s+type="[^"]*"', '<sampler type="%s"' % sampler, text)
    if n != 1:
        raise ValueError("%s: expected one <sampler type=...> element, found %d" % (xml_path, n))
    resolver = mi.file_resolver() if hasattr(mi, "file_resolver") else mi.Thread.thread().file_resolver()
    resolver.prepend(os.path.dirname(os.path.abspath(xml_path)))
    return mi.load_string(text)


def set_depth(text, max_depth, rr_depth):
    """The XML text with the path integrator's max_depth (Mitsuba's count) and rr_depth set, when > 0."""
    m = re.search(r'<integrator\s+type="path"\s*>', text)
    if not m:
        raise ValueError("expected a <integrator type=\"path\"> element")
    if max_depth > 0:
        text, n = re.subn(r'(<integer\s+name="max_depth"\s+value=")[^"]*"', r'\g<1>%d"' % max_depth, text)
        if n != 1:
            raise ValueError("expected one max_depth in the integrator, found %d" % n)
    if rr_depth > 0:
        if re.search(r'name="rr_depth"', text):
            raise ValueError("the XML already sets rr_depth")
        text = text[:m.end()] + '<integer name="rr_depth" value="%d"/>' % rr_depth + text[m.end():]
    return text


def render(mi, dr, scene, spp, seed):
    """One render: (seconds, image tensor, sample count used). The image is evaluated inside the timing."""
    t0 = time.perf_counter()
    img = mi.render(scene, spp=spp, seed=seed)
    dr.eval(img)
    dr.sync_thread()
    t = time.perf_counter() - t0
    return t, img, scene.sensors()[0].sampler().sample_count()


def cmd_series(a):
    mi, dr = load_mitsuba()
    rw, rh, ref = read_pfm(a.ref)
    samplers = a.samplers.split(",")
    scenes = {s: load_scene(mi, a.xml, s) for s in samplers}
    ladders = {}
    out = open(a.out, "w") if a.out else sys.stdout
    out.write("sampler\tseed\tspp\tspp_used\tseconds\trelmse\tbias\n")
    for seed in range(1, a.seeds + 1):
        for s in samplers:
            sc = scenes[s]
            spp, k, prev = 1, 0, 0.0
            while True:
                if seed == 1:
                    if prev < WARMUP_BELOW:
                        render(mi, dr, sc, spp, WARMUP_SEED)  # compiles this configuration's kernels
                elif k >= ladders[s]:
                    break
                t, img, used = render(mi, dr, sc, spp, seed)
                w, h, px = image_floats(dr, img)
                if (w, h) != (rw, rh):
                    raise ValueError("render is %dx%d, reference %s is %dx%d" % (w, h, a.ref, rw, rh))
                e, b = measure(px, ref)
                if a.keep:
                    write_pfm(os.path.join(a.keep, "%s-s%d-%d.pfm" % (s, seed, spp)), w, h, px)
                prev = t
                out.write("%s\t%d\t%d\t%d\t%.6g\t%.6g\t%.6g\n" % (s, seed, spp, used, t, e, b))
                out.flush()
                k += 1
                if seed == 1 and (t >= a.budget or e < FLOOR_STOP * a.floor or 2 * spp > a.max_spp):
                    ladders[s] = k
                    break
                spp *= 2
    if out is not sys.stdout:
        out.close()
    return 0


def cmd_serve(a):
    """Renders on request, for bench.c's throughput part (which times pdftrace between these renders).
    Reads one command per line on standard input and answers each with one line:
      load NAME XML SAMPLER MAX_DEPTH RR_DEPTH  -> "ok"  (the scene, its sampler and depths set; 0 keeps the XML's)
      render NAME SPP SEED BLOCKS               -> "ok SECONDS SPP_USED WIDTH HEIGHT MEAN_R MEAN_G MEAN_B M_0 .. M_B-1"
      drop NAME                                 -> "ok"
    or "error WHY" (and goes on). SECONDS is the render alone (as render()); MEAN_* are the image's
    means per channel, M_b the mean over channels and the pixels i (row-major) with i mod BLOCKS = b:
    for bench.c's check that both renderers compute the same image."""
    mi, dr = load_mitsuba()
    scenes = {}
    for line in sys.stdin:
        w = line.split()
        try:
            if len(w) == 6 and w[0] == "load":
                scenes[w[1]] = load_scene(mi, w[2], w[3], int(w[4]), int(w[5]))
                reply = "ok"
            elif len(w) == 5 and w[0] == "render":
                t, img, used = render(mi, dr, scenes[w[1]], int(w[2]), int(w[3]))
                iw, ih, px = image_floats(dr, img)
                nb, n = int(w[4]), iw * ih
                means = [sum(px[c::3]) / n for c in range(3)]
                blocks = [sum(sum(px[3 * b + c::3 * nb]) for c in range(3)) / (3 * ((n - b + nb - 1) // nb))
                          for b in range(nb)]
                reply = "ok %.9g %d %d %d %.9g %.9g %.9g" % (t, used, iw, ih, means[0], means[1], means[2])
                reply += "".join(" %.9g" % v for v in blocks)
            elif len(w) == 2 and w[0] == "drop":
                scenes.pop(w[1], None)
                reply = "ok"
            else:
                reply = "error unknown command: %s" % line.strip()
        except Exception as e:  # a bad scene or render: say why on the same line, keep serving
            reply = "error %s" % str(e).replace("\n", " ")
        sys.stdout.write(reply + "\n")
        sys.stdout.flush()
    return 0


def region_stats(px, w, h, n=4):
    """Per-channel means of the whole image and of n x n regions: (whole[3], regions[n*n][3])."""
    whole = [0.0, 0.0, 0.0]
    reg = [[0.0, 0.0, 0.0] for _ in range(n * n)]
    cnt = [0] * (n * n)
    for y in range(h):
        ry = y * n // h
        for x in range(w):
            q = ry * n + x * n // w
            i = 3 * (y * w + x)
            cnt[q] += 1
            for c in range(3):
                whole[c] += px[i + c]
                reg[q][c] += px[i + c]
    return [v / (w * h) for v in whole], [[v / cnt[q] for v in reg[q]] for q in range(n * n)]


def cmd_refcheck(a):
    mi, dr = load_mitsuba()
    refs = [read_pfm(path) for path in a.ref]
    sc = load_scene(mi, a.xml, "independent")
    wholes, regs = [], []
    t0 = time.perf_counter()
    for seed in range(1, a.seeds + 1):
        _, img, _ = render(mi, dr, sc, a.spp, a.seed_base + seed)
        w, h, px = image_floats(dr, img)
        for path, (rw, rh, _) in zip(a.ref, refs):
            if (w, h) != (rw, rh):
                raise ValueError("render is %dx%d, reference %s is %dx%d" % (w, h, path, rw, rh))
        wh, rg = region_stats(px, w, h)
        wholes.append(wh)
        regs.append(rg)
    seconds = time.perf_counter() - t0
    for path, (rw, rh, ref) in zip(a.ref, refs):
        report_refcheck(a, path, seconds, wholes, regs, region_stats(ref, rw, rh))
    return 0


def report_refcheck(a, path, seconds, wholes, regs, ref_stats):
    """Prints the mean and 4x4-region comparison of the seeds' renders with one reference."""
    rwhole, rreg = ref_stats
    k = len(wholes)
    # the reference's own noise: with the same variance per sample as Mitsuba's, its SE is Mitsuba's
    # SE of the mean times sqrt(K N / R), R the reference's spp (a stated assumption, not a measurement)
    inflate = math.sqrt(1.0 + k * a.spp / a.ref_spp) if a.ref_spp > 0 else 1.0

    def stat(vals, rv):
        m = sum(vals) / k
        se = math.sqrt(sum((v - m) ** 2 for v in vals) / (k - 1) / k)
        return (m / rv - 1.0 if rv > 0 else float("nan"), (m - rv) / se if se > 0 else float("nan"),
                se / rv if rv > 0 else float("nan"))

    print("# refcheck %s against %s: %d seeds x %d spp (%.0f s); z = (Mitsuba - ref) / SE(Mitsuba seeds)%s"
          % (a.xml, path, k, a.spp, seconds,
             "; z_both also counts the reference's noise (%d spp, same variance per sample assumed)" % a.ref_spp
             if a.ref_spp > 0 else ""))
    print("what\tchannel\tmitsuba_over_ref_minus_1\tse_rel\tz\tz_both")
    for c, name in enumerate("RGB"):
        d, z, se = stat([wv[c] for wv in wholes], rwhole[c])
        print("mean\t%s\t%+.5f\t%.5f\t%+.2f\t%+.2f" % (name, d, se, z, z / inflate))
    n3 = n2 = 0
    zmax = 0.0
    for q in range(len(rreg)):
        for c, name in enumerate("RGB"):
            d, z, se = stat([rg[q][c] for rg in regs], rreg[q][c])
            print("region%d,%d\t%s\t%+.5f\t%.5f\t%+.2f\t%+.2f" % (q % 4, q // 4, name, d, se, z, z / inflate))
            n3 += abs(z) > 3
            n2 += abs(z / inflate) > 3
            zmax = max(zmax, abs(z))
    print("# regions x channels beyond 3 SE: %d of %d (with the reference's noise: %d); largest |z| %.2f"
          % (n3, 3 * len(rreg), n2, zmax))


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    sub = p.add_subparsers(dest="cmd", required=True)
    sub.add_parser("check")
    sub.add_parser("serve")
    s = sub.add_parser("series")
    s.add_argument("--xml", required=True)
    s.add_argument("--ref", required=True)
    s.add_argument("--floor", type=float, default=0.0)
    s.add_argument("--budget", type=float, required=True, help="stop once one render takes this many seconds")
    s.add_argument("--seeds", type=int, default=5)
    s.add_argument("--samplers", default="independent,multijitter")
    s.add_argument("--max-spp", type=int, default=1 << 19)
    s.add_argument("--out", help="TSV file (default: standard output)")
    s.add_argument("--keep", help="also write every render as DIR/SAMPLER-sSEED-SPP.pfm")
    r = sub.add_parser("refcheck")
    r.add_argument("--xml", required=True)
    r.add_argument("--ref", required=True, nargs="+", help="one or more reference PFMs")
    r.add_argument("--spp", type=int, required=True)
    r.add_argument("--seeds", type=int, default=8)
    r.add_argument("--ref-spp", type=int, default=0, help="the reference's spp (for z_both)")
    r.add_argument("--seed-base", type=int, default=1000, help="seeds seed_base+1 .. seed_base+K")
    a = p.parse_args()
    try:
        if a.cmd == "check":
            load_mitsuba()
            return 0
        if a.cmd == "serve":
            return cmd_serve(a)
        if a.cmd == "series":
            if a.seeds < 1 or a.budget <= 0:
                p.error("--seeds must be >= 1 and --budget > 0")
            return cmd_series(a)
        if a.seeds < 2 or a.spp < 1:
            p.error("refcheck needs --seeds >= 2 and --spp >= 1")
        return cmd_refcheck(a)
    except ImportError as e:
        print("mitsuba_series.py: cannot import Mitsuba 3 (%s)" % e, file=sys.stderr)
        return 1
    except Exception as e:  # a scene, file or variant problem: the reason, exit 1
        print("mitsuba_series.py: %s" % e, file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
