#!/usr/bin/env python3
"""mitsuba_render.py - renders a Mitsuba 3 scene (an XML written by pdftrace --export-mitsuba) with
K independent seeds for `make validate` and writes, in the layout build/ptv reads:

  PREFIX.pfm          the mean of the K seed images (little-endian colour PFM, bottom row first)
  PREFIX-var.pfm      per pixel and channel, the variance of that mean: the sample variance of the
                      K seed images divided by K (K - 1 degrees of freedom)
  PREFIX-regions.txt  per seed, the mean of each of 4 x 4 image regions per channel (see below)

  usage: mitsuba_render.py SCENE.xml PREFIX SEEDS SPP [FIRST_SEED]
         mitsuba_render.py --check      the Mitsuba version and the variant it would use

Each seed is a separate mi.render(scene, spp=SPP, seed=FIRST_SEED + k) with the scene's own
(independent) sampler, so the K images are independent. Any Mitsuba warning or error fails the
run (the logger's error level is set to Warn) and nothing is written. The variant is
$MITSUBA_VARIANT if set, else llvm_ad_rgb when a shared libLLVM works here, else scalar_rgb
(with a note on stderr). Needs only mitsuba and drjit (no numpy).

Regions: pixel (x, y), y counted from the top row, belongs to region (4x // W, 4y // H); the
file is "pt-regions W H K DOF" (DOF = K - 1: the degrees of freedom of PREFIX-var.pfm), then K
lines of 48 numbers: R G B of each region in row-major region order (top-left first).
build/ptv's `render ... SEEDS REGIONS.txt` writes the same layout.
"""
import glob
import os
import re
import subprocess
import sys
import time

# libLLVM locations on Debian/Ubuntu (libllvmNN) and other common layouts.
LLVM_GLOBS = ["/usr/lib/*/libLLVM*.so*", "/usr/lib/llvm-*/lib/libLLVM*.so*", "/usr/lib64/libLLVM*.so*",
              "/usr/local/lib/libLLVM*.so*"]

# A scene small enough to probe the LLVM variant in a few seconds.
PROBE = """
import mitsuba as mi
mi.set_variant('llvm_ad_rgb')
s = mi.load_dict({'type': 'scene', 'i': {'type': 'path'}, 'e': {'type': 'constant'},
                  'b': {'type': 'sphere', 'bsdf': {'type': 'dielectric'}},
                  'c': {'type': 'perspective', 'film': {'type': 'hdrfilm', 'width': 4, 'height': 4}}})
mi.render(s, spp=2)
"""


def llvm_version(path):
    """The major version in a libLLVM file name (libLLVM-19.so, libLLVM.so.19.1), else 0."""
    m = re.search(r"libLLVM[-.]?(?:so\.)?(\d+)", os.path.basename(path))
    return int(m.group(1)) if m else 0


def find_libllvm():
    """The newest libLLVM on the machine (drjit can pick an older one that miscompiles), or None."""
    found = [p for g in LLVM_GLOBS for p in glob.glob(g) if os.path.isfile(p)]
    return max(found, key=lambda p: (llvm_version(p), -len(p))) if found else None


def choose_variant():
    """llvm_ad_rgb if a probe render in a child process succeeds, else scalar_rgb (with a note)."""
    if os.environ.get("MITSUBA_VARIANT"):
        return os.environ["MITSUBA_VARIANT"]
    if not os.environ.get("DRJIT_LIBLLVM_PATH"):
        lib = find_libllvm()
        if lib:
            os.environ["DRJIT_LIBLLVM_PATH"] = lib
    try:
        ok = subprocess.run([sys.executable, "-c", PROBE], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            timeout=300).returncode == 0
    except subprocess.TimeoutExpired:
        ok = False
    if ok:
        return "llvm_ad_rgb"
    print("mitsuba_render: note: llvm_ad_rgb does not work here (no usable libLLVM; apt-get install libllvm19, "
          "or set DRJIT_LIBLLVM_PATH): using scalar_rgb, which is slower", file=sys.stderr)
    return "scalar_rgb"


def write_pfm(path, w, h, values):
    """values: w*h*3 floats, top row first; PFM stores the bottom row first (scale -1: little-endian)."""
    import struct
    row = 3 * w
    tmp = path + ".tmp"
    with open(tmp, "wb") as f:
        f.write(b"PF\n%d %d\n-1\n" % (w, h))
        for y in range(h - 1, -1, -1):
            f.write(struct.pack("<%df" % row, *values[y * row:(y + 1) * row]))
    os.replace(tmp, path)


def region_means(img, w, h):
    """The 4 x 4 region means of one image (list of w*h*3, top row first): 48 numbers."""
    sums = [0.0] * 48
    counts = [0] * 16
    for y in range(h):
        ry = 4 * y // h
        for x in range(w):
            r = 4 * ry + 4 * x // w
            i = 3 * (y * w + x)
            counts[r] += 1
            for c in range(3):
                sums[3 * r + c] += img[i + c]
    return [sums[k] / counts[k // 3] if counts[k // 3] else 0.0 for k in range(48)]


def check():
    """Prints what a render would use; fails when mitsuba does not import."""
    variant = choose_variant()
    import mitsuba as mi
    mi.set_variant(variant)
    print("mitsuba %s, variant %s%s" % (mi.__version__, variant, " (DRJIT_LIBLLVM_PATH=%s)" %
          os.environ["DRJIT_LIBLLVM_PATH"] if variant.startswith("llvm") and os.environ.get("DRJIT_LIBLLVM_PATH") else ""))
    return 0


def main(argv):
    if len(argv) == 2 and argv[1] == "--check":
        return check()
    if len(argv) not in (5, 6):
        print("usage: mitsuba_render.py SCENE.xml PREFIX SEEDS SPP [FIRST_SEED]", file=sys.stderr)
        return 2
    xml, prefix = argv[1], argv[2]
    try:
        seeds, spp = int(argv[3]), int(argv[4])
        first = int(argv[5]) if len(argv) == 6 else 1000
    except ValueError:
        print("mitsuba_render: SEEDS, SPP and FIRST_SEED must be integers", file=sys.stderr)
        return 2
    if seeds < 2 or spp < 1:
        print("mitsuba_render: need SEEDS >= 2 (the variance comes from the seeds) and SPP >= 1", file=sys.stderr)
        return 2
    variant = choose_variant()
    import mitsuba as mi
    mi.set_variant(variant)
    # A warning (unknown parameter, unused property, ...) becomes an exception: the run fails.
    logger = mi.logger() if hasattr(mi, "logger") else mi.Thread.thread().logger()
    logger.set_error_level(mi.LogLevel.Warn)
    try:
        scene = mi.load_file(xml)
        film = scene.sensors()[0].film()
        w, h = film.crop_size()[0], film.crop_size()[1]
        n = 3 * w * h
        s1, s2, regions = [0.0] * n, [0.0] * n, []
        mi.render(scene, spp=1, seed=0)  # compiles the kernels, so the timed renders run warm
        t0 = time.time()
        for k in range(seeds):
            img = mi.render(scene, spp=spp, seed=first + k)
            if img.shape[2] != 3:
                raise RuntimeError("expected an RGB film (pixel_format rgb), got %d channels" % img.shape[2])
            vals = list(img.array)  # row-major, top row first, RGB interleaved
            for i, v in enumerate(vals):
                s1[i] += v
                s2[i] += v * v
            regions.append(region_means(vals, w, h))
        seconds = time.time() - t0
    except Exception as e:  # Mitsuba reports load and render problems (and warnings, see above) as exceptions
        print("mitsuba_render: %s: %s" % (xml, str(e).strip()), file=sys.stderr)
        return 1
    mean = [v / seeds for v in s1]
    # Sample variance of the K images, divided by K: the variance of their mean.
    var = [max(0.0, (s2[i] - s1[i] * mean[i]) / (seeds - 1)) / seeds for i in range(n)]
    write_pfm(prefix + ".pfm", w, h, mean)
    write_pfm(prefix + "-var.pfm", w, h, var)
    tmp = prefix + "-regions.txt.tmp"
    with open(tmp, "w") as f:
        f.write("pt-regions %d %d %d %d\n" % (w, h, seeds, seeds - 1))
        for r in regions:
            f.write(" ".join("%.9g" % v for v in r) + "\n")
    os.replace(tmp, prefix + "-regions.txt")
    print("mitsuba_render: %s: %dx%d, %d seeds x %d spp, %s, %.1f s" % (xml, w, h, seeds, spp, variant, seconds))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
