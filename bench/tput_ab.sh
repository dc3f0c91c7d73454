#!/bin/sh
# bench/tput_ab.sh - samples/s of two revisions of pdftrace.h side by side at the throughput
# settings (bench/tput_ab.c): for each scene, REPS repetitions, each running A and B once with
# the repetition's seed, in alternating order (ABBA), so that load changes on a shared machine
# hit both alike. Prints the medians of each and the median (and range) of the paired ratios B/A,
# per CPU second (the figure to read with 1 thread) and per wall second.
#
#   bench/tput_ab.sh [-r REPS] [-t THREADS] [-i 0|1|2] [-s 0|1|2] REV_A REV_B
#
# A revision is anything `git show REV:pdftrace.h` takes, or `.` for the working tree.
# -i: the integrator (0 default, 1 scalar, 2 batched); -s: 0 the throughput settings (independent
# numbers), 1 the same with the Sobol sampler, 2 each scene file's own settings (Sobol,
# indirect_paths, roulette: a default render). Run from the repository root.
set -eu
reps=7; threads=1; integ=0; sampler=0
while getopts r:t:i:s: o; do
    case $o in r) reps=$OPTARG ;; t) threads=$OPTARG ;; i) integ=$OPTARG ;; s) sampler=$OPTARG ;; *) exit 2 ;; esac
done
shift $((OPTIND - 1))
[ $# -eq 2 ] || { echo "usage: bench/tput_ab.sh [-r REPS] [-t THREADS] [-i 0|1|2] [-s 0|1|2] REV_A REV_B" >&2; exit 2; }
dir=build/tput-ab
mkdir -p "$dir/a" "$dir/b"
for side in a b; do
    if [ $side = a ]; then rev=$1; else rev=$2; fi
    for f in pdftrace.h pdftrace_scene.h; do
        if [ "$rev" = . ]; then cp "$f" "$dir/$side/$f"; else git show "$rev:$f" > "$dir/$side/$f"; fi
    done
    ${CC:-cc} -I"$dir/$side" -std=c99 -O3 -pthread -o "$dir/$side/tput_ab" bench/tput_ab.c -lm
done
# scene, width, height, spp: the throughput part's sizes, about a second each on one thread
for spec in "bench/scenes/rooms.scene 160 120 64" "scenes/cornell-diffuse.scene 600 600 4"; do
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
