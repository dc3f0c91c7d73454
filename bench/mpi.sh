#!/usr/bin/env bash
# mpi.sh - the MPI benchmark (make bench-mpi; docs/mpi.md):
#     bench/mpi.sh build/pdftrace_mpi build/bench_mpi_gather OUTDIR
# 1. Ranks against threads on this machine: the same render (scenes/cornell.scene at
#    BENCH_MPI_SIZE, BENCH_MPI_SPP samples) as 1 rank x 2 threads and as 2 ranks x 1 thread,
#    alternated BENCH_MPI_RUNS times; the median wall clock of the whole mpirun (start-up
#    included) and of the render as pdftrace reports it (the slowest rank, gather included), and
#    the ratio. The images are compared too (they must be the same bytes).
# 2. The gather alone as the image grows (bench/mpi_gather.c), with 2 and 3 ranks.
# Writes OUTDIR/summary.md and prints it.
set -eu
[ $# -eq 3 ] || { echo "usage: $0 PDFTRACE_MPI BENCH_MPI_GATHER OUTDIR" >&2; exit 2; }
P=$1 G=$2 OUT=$3
MPIRUN=${MPIRUN:-mpirun}
SIZE=${BENCH_MPI_SIZE:-320x240}
SPP=${BENCH_MPI_SPP:-256}
RUNS=${BENCH_MPI_RUNS:-5}
mkdir -p "$OUT"
FLAGS=()
if "$MPIRUN" --version 2>&1 | grep -q "Open MPI"; then
    FLAGS+=(--oversubscribe)
    [ "$(id -u)" = 0 ] && FLAGS+=(--allow-run-as-root)
fi
median() { sort -g | awk '{a[NR] = $1} END {print a[int((NR + 1) / 2)]}'; }
now() { date +%s.%N; }

one() { # ranks threads tag run -> appends "wall render" to OUT/tag.txt
    local t0 t1
    t0=$(now)
    "$MPIRUN" -q "${FLAGS[@]}" -np "$1" "$P" scenes/cornell.scene --size "$SIZE" --spp "$SPP" --threads "$2" \
        -o "$OUT/$3.pfm" >"$OUT/$3.log" 2>&1
    t1=$(now)
    echo "$(echo "$t1 - $t0" | bc) $(awk '/^time/ {print $2}' "$OUT/$3.log")" >>"$OUT/$3.txt"
}
rm -f "$OUT"/r1t2.txt "$OUT"/r2t1.txt
for i in $(seq 1 "$RUNS"); do
    one 1 2 r1t2
    one 2 1 r2t1
done
same=no
cmp -s "$OUT/r1t2.pfm" "$OUT/r2t1.pfm" && same=yes
w12=$(cut -d' ' -f1 "$OUT/r1t2.txt" | median) r12=$(cut -d' ' -f2 "$OUT/r1t2.txt" | median)
w21=$(cut -d' ' -f1 "$OUT/r2t1.txt" | median) r21=$(cut -d' ' -f2 "$OUT/r2t1.txt" | median)
{
    echo "## Ranks against threads ($(getconf _NPROCESSORS_ONLN) cores; cornell.scene $SIZE, $SPP spp; median of $RUNS, alternated)"
    echo
    echo "| run | wall clock of mpirun (s) | render, as reported (s) |"
    echo "|---|---|---|"
    echo "| 1 rank x 2 threads | $w12 | $r12 |"
    echo "| 2 ranks x 1 thread | $w21 | $r21 |"
    echo "| ratio (2x1 / 1x2) | $(echo "scale=3; $w21 / $w12" | bc) | $(echo "scale=3; $r21 / $r12" | bc) |"
    echo
    echo "The two PFMs are the same bytes: $same."
    echo
    echo "## The gather alone (bench/mpi_gather.c: rank 0 receives and adds every rank's film in rank order)"
    echo
    "$MPIRUN" -q "${FLAGS[@]}" -np 2 "$G"
    "$MPIRUN" -q "${FLAGS[@]}" -np 3 "$G" | tail -n +3
} >"$OUT/summary.md"
cat "$OUT/summary.md"
