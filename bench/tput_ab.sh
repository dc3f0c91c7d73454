#!/bin/sh
# bench/tput_ab.sh - samples/s of two revisions of pdftrace.h side by side at the throughput
# settings (bench/tput_ab.c): for each scene, REPS repetitions, each running A and B once with
# the repetition's seed, in alternating order (ABBA), so that load changes on a shared machine
# hit both alike. Prints the medians of each and the median (and range) of the paired ratios B/A,
# per CPU second (the figure to read with 1 thread) and per wall second.
#
#   bench/tput_ab.sh [-r REPS] [-t THREADS] [-i 0|1|2] [-s 0|1|2] [-e] REV_A REV_B
#
# A revision is anything `git show REV:pdftrace.h` takes, or `.` for the working tree.
# -i: the integrator (0 default, 1 scalar, 2 batched); -s: 0 the throughput settings (independent
# numbers), 1 the same with the Sobol sampler, 2 each scene file's own settings (Sobol,
# indirect_paths, roulette: a default render); -e: both built with Embree (-DPDFTRACE_EMBREE,
# -lembree3) and rendering with the Embree backend, and three more scenes: many-tris (1049
# primitives), nine tori of scenes/mesh.obj (20738 primitives) and a heightfield of 20000
# triangles (both large enough for Embree under AUTO). TPUT_AB_SCENES="FILE W H SPP|..." replaces
# the scene list (e.g. "bench/scenes/door.scene 128 128 32"). Run from the repository root.
set -eu
reps=7; threads=1; integ=0; sampler=0; embree=0
while getopts r:t:i:s:e o; do
    case $o in r) reps=$OPTARG ;; t) threads=$OPTARG ;; i) integ=$OPTARG ;; s) sampler=$OPTARG ;; e) embree=1 ;; *) exit 2 ;; esac
done
shift $((OPTIND - 1))
[ $# -eq 2 ] || { echo "usage: bench/tput_ab.sh [-r REPS] [-t THREADS] [-i 0|1|2] [-s 0|1|2] [-e] REV_A REV_B" >&2; exit 2; }
dir=build/tput-ab
mkdir -p "$dir/a" "$dir/b"
eflags=; elibs=; scenes="bench/scenes/rooms.scene 160 120 64|scenes/cornell-diffuse.scene 600 600 4"
if [ $embree = 1 ]; then
    eflags=-DPDFTRACE_EMBREE; elibs=-lembree3
    { printf 'size 160 120\ncamera look_from 0 5 -9 look_at 0 0.5 0 vfov 50\n'
      printf 'material floor lambertian 0.7 0.7 0.7\nmaterial gold lambertian 0.8 0.6 0.2\nmaterial lamp emitter 6 6 6\n'
      printf 'quad -8 0 -8   0 0 16   16 0 0   floor\nquad -2 6 -2   4 0 0   0 0 4   lamp\n'
      for x in -2.5 0 2.5; do for z in -2.5 0 2.5; do
          printf 'identity\nrotate 1 0 0 -30\ntranslate %s 0.7 %s\nmesh mesh.obj gold\n' $x $z
      done; done; } > "$dir/tori.scene"
    cp scenes/mesh.obj "$dir/mesh.obj"
    python3 - "$dir/terrain.obj" <<'PY'
import math, sys
n = 100  # a 100 x 100 heightfield: 20000 triangles
with open(sys.argv[1], 'w') as f:
    for j in range(n + 1):
        for i in range(n + 1):
            x, z = -5 + 10 * i / n, -5 + 10 * j / n
            f.write(f"v {x:.5f} {0.6 * math.sin(1.7 * x) * math.cos(1.3 * z) + 0.25 * math.sin(4.1 * x + 2.3 * z):.5f} {z:.5f}\n")
    for j in range(n):
        for i in range(n):
            a = j * (n + 1) + i + 1
            f.write(f"f {a} {a + n + 1} {a + 1}\nf {a + 1} {a + n + 1} {a + n + 2}\n")
PY
    printf 'size 160 120\ncamera look_from 0 4 -8 look_at 0 0 0 vfov 50\nmaterial ground lambertian 0.6 0.55 0.5\nmaterial lamp emitter 8 8 8\nmesh terrain.obj ground\nquad -1 5 -1   2 0 0   0 0 2   lamp\n' > "$dir/terrain.scene"
    scenes="$scenes|bench/scenes/many-tris.scene 128 96 16|$dir/tori.scene 160 120 64|$dir/terrain.scene 160 120 32"
fi
scenes=${TPUT_AB_SCENES:-$scenes}
for side in a b; do
    if [ $side = a ]; then rev=$1; else rev=$2; fi
    for f in pdftrace.h pdftrace_scene.h; do
        if [ "$rev" = . ]; then cp "$f" "$dir/$side/$f"; else git show "$rev:$f" > "$dir/$side/$f"; fi
    done
    # a revision from before the batched integrator has no pt_render_desc.integrator
    oflags=; grep -q PT_INTEGRATOR_BATCHED "$dir/$side/pdftrace.h" || oflags=-DTPUT_AB_NO_INTEGRATOR
    ${CC:-cc} -I"$dir/$side" $eflags $oflags -std=c99 -O3 -pthread -o "$dir/$side/tput_ab" bench/tput_ab.c $elibs -lm
done
# scene, width, height, spp: the throughput part's sizes, about a second each on one thread
IFS='|'; set -f
for spec in $scenes; do
    unset IFS; set +f
    : > "$dir/runs"
    r=1
    while [ $r -le "$reps" ]; do
        if [ $((r % 2)) -eq 1 ]; then order="a b"; else order="b a"; fi
        for side in $order; do
            # shellcheck disable=SC2086
            echo "$r $side $("$dir/$side/tput_ab" $spec "$threads" "$integ" "$r" "$sampler")" >> "$dir/runs"
        done
        r=$((r + 1))
    done
    python3 - "$dir/runs" "${spec%% *}" "$threads" <<'PY'
import statistics as st, sys
rows = [l.split() for l in open(sys.argv[1])]
run = {(int(r[0]), r[1]): r for r in rows}
reps = sorted({k[0] for k in run})
def col(side, i): return [float(run[(r, side)][i]) for r in reps]
same = all(run[(r, 'a')][4] == run[(r, 'b')][4] for r in reps)
print(f"{sys.argv[2]} ({sys.argv[3]} thread(s), {len(reps)} reps; images {'identical' if same else 'differ'}):")
for i, what in ((2, 'M samples per CPU s'), (3, 'M samples per wall s')):
    a, b = col('a', i), col('b', i)
    ratio = [y / x for x, y in zip(a, b)]
    print(f"  {what:22s} A {st.median(a):.4f}  B {st.median(b):.4f}  B/A {st.median(ratio):.3f} "
          f"({min(ratio):.3f}-{max(ratio):.3f})")
PY
done
