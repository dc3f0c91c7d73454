#!/usr/bin/env bash
# mpi_test.sh - the pdftrace command under MPI (make mpi-test; tools/pdftrace.c built with
# -DPDFTRACE_MPI, pdftrace_mpi.h):
#     tests/mpi/mpi_test.sh build/pdftrace_mpi scenes WORKDIR
# Runs 1, 2 and 3 ranks on this machine (Open MPI: --oversubscribe, and --allow-run-as-root as
# root) and checks that the PFM (and EXR, when built with OpenEXR) written with 2 and 3 ranks
# equals the one-rank file byte for byte, for the independent and Sobol samplers, MIS and
# mixture, with and without adaptive sampling (pilot and own-samples), and with ranks x threads;
# that the one-rank file equals the command without mpirun; and that a failing rank ends the job
# with one clear line and no output file: a bad scene path on one rank, another scene on one
# rank, guiding (which cannot be split), a rank killed while rendering.
# Prints "PASS mpi.name (details)" / "FAIL mpi.name: reason" per test and as its last line
# "N passed, M failed, 0 skipped"; exit status 0 iff nothing failed.
set -u

if [ $# -ne 3 ]; then
    echo "usage: $0 PDFTRACE_MPI SCENEDIR WORKDIR" >&2
    exit 2
fi
abspath() { case $1 in /*) printf '%s\n' "$1" ;; *) printf '%s/%s\n' "$PWD" "$1" ;; esac; }
P=$(abspath "$1")
S=$(abspath "$2")
W=$(abspath "$3")
MPIRUN=${MPIRUN:-mpirun}
rm -rf "$W"
mkdir -p "$W" || exit 2

passed=0 failed=0
pass() { printf 'PASS mpi.%s (%s)\n' "$1" "$2"; passed=$((passed + 1)); }
fail() { printf 'FAIL mpi.%s: %s\n' "$1" "$2"; failed=$((failed + 1)); }

# Open MPI refuses root and more ranks than cores unless told; MPICH takes neither flag.
MPIFLAGS=()
if "$MPIRUN" --version 2>&1 | grep -q "Open MPI"; then
    MPIFLAGS+=(--oversubscribe)
    [ "$(id -u)" = 0 ] && MPIFLAGS+=(--allow-run-as-root)
fi
have_exr=0
case $("$P" --version 2>&1) in *"OpenEXR yes"*) have_exr=1 ;; esac

# ---- bit-identical outputs: 1, 2 and 3 ranks
BASE=(-q --size 40x30 --spp 24 --seed 5)
t_identical() { # name, options...
    local name=$1 n out ext ok=1 why="" sizes=""
    shift
    for n in 1 2 3; do
        out=("-o" "$W/$name-$n.pfm")
        [ $have_exr = 1 ] && out+=("-o" "$W/$name-$n.exr")
        if ! "$MPIRUN" -q "${MPIFLAGS[@]}" -np $n "$P" "$S/cornell.scene" "${BASE[@]}" "$@" "${out[@]}" \
            >"$W/$name-$n.out" 2>"$W/$name-$n.err"; then
            ok=0 why="$n ranks: exit status $? ($(head -n 1 "$W/$name-$n.err"))"
            break
        fi
        for ext in pfm $([ $have_exr = 1 ] && echo exr); do
            if [ $n -gt 1 ] && ! cmp -s "$W/$name-1.$ext" "$W/$name-$n.$ext"; then
                ok=0 why="$n ranks: $name-$n.$ext differs from one rank's"
            fi
        done
        sizes="$sizes $(wc -c <"$W/$name-$n.pfm")"
    done
    if [ $ok = 1 ]; then
        pass "identical_$name" "1, 2, 3 ranks: the same $([ $have_exr = 1 ] && echo 'PFM and EXR' || echo PFM) bytes; $*"
    else
        fail "identical_$name" "$why"
    fi
}
t_identical indep_mis --sampler independent --strategy mis --threads 1
t_identical indep_mixture --sampler independent --strategy mixture --threads 1
t_identical sobol_mis --sampler sobol --strategy mis --threads 1
t_identical sobol_mixture --sampler sobol --strategy mixture --threads 1
t_identical indep_adaptive --sampler independent --strategy mis --adaptive 0.05 --threads 1
t_identical sobol_adaptive --sampler sobol --strategy mixture --adaptive 0.05 --threads 1
t_identical indep_adaptive_own --sampler independent --strategy mixture --adaptive 0.05 --adaptive-mode own-samples --threads 1
t_identical sobol_adaptive_own --sampler sobol --strategy mis --adaptive 0.05 --adaptive-mode own-samples --threads 1
t_identical ranks_x_threads --sampler sobol --strategy mis --adaptive 0.05 --threads 2

# the one-rank file is the command's without mpirun (the whole render: no split)
"$P" "$S/cornell.scene" "${BASE[@]}" --sampler sobol --strategy mis --threads 1 -o "$W/plain.pfm" 2>"$W/plain.err"
if cmp -s "$W/plain.pfm" "$W/sobol_mis-1.pfm"; then
    pass plain_equals_one_rank "the command without mpirun writes the same PFM"
else
    fail plain_equals_one_rank "without mpirun: another PFM ($(head -n 1 "$W/plain.err"))"
fi
# the stats of 3 ranks: rank 0 reports the summed samples, once
"$MPIRUN" "${MPIFLAGS[@]}" -np 3 "$P" "$S/cornell.scene" --size 40x30 --spp 24 --threads 1 -o "$W/stats.pfm" \
    >"$W/stats.out" 2>"$W/stats.err"
if grep -q '^samples    28800 ' "$W/stats.out" && [ "$(grep -c '^samples' "$W/stats.out")" = 1 ] &&
    grep -q '^mpi        3 ranks' "$W/stats.out"; then
    pass stats "rank 0 alone prints, with the samples of all ranks: $(grep '^samples' "$W/stats.out")"
else
    fail stats "stats of 3 ranks: '$(grep -E '^(samples|mpi)' "$W/stats.out" | tr '\n' ' ')'"
fi

# ---- failures: one clear line, a non-zero exit status, no output file
t_fails() { # name, expected text, then the mpirun arguments after the flags
    local name=$1 want=$2 status=0 left
    shift 2
    rm -f "$W/fail.pfm"
    "$MPIRUN" -q "${MPIFLAGS[@]}" "$@" >"$W/$name.out" 2>"$W/$name.err" || status=$?
    left=$(ls "$W" | grep -c '^fail\.pfm' || true)
    if [ $status != 0 ] && [ "$left" = 0 ] && [ "$(wc -l <"$W/$name.err")" = 1 ] && grep -q -- "$want" "$W/$name.err"; then
        pass "$name" "exit status $status, no file: $(head -n 1 "$W/$name.err")"
    else
        fail "$name" "exit status $status, $left output files, stderr: '$(head -n 3 "$W/$name.err" | tr '\n' '|')'"
    fi
}
GOOD=("$P" "$S/cornell.scene" -q --size 40x30 --spp 8 -o "$W/fail.pfm")
t_fails bad_scene_one_rank "rank 1: .*no-such.scene" -np 1 "${GOOD[@]}" : -np 1 "$P" "$S/no-such.scene" -q --size 40x30 \
    --spp 8 -o "$W/fail.pfm"
t_fails bad_scene_rank0 "rank 0: .*no-such.scene" -np 1 "$P" "$S/no-such.scene" -q -o "$W/fail.pfm" : -np 2 "${GOOD[@]}"
t_fails other_scene_one_rank "rank 2: .*differ from rank 0" -np 2 "${GOOD[@]}" : -np 1 "$P" "$S/glass.scene" -q \
    --size 40x30 --spp 8 -o "$W/fail.pfm"
t_fails other_spp_one_rank "rank 1: .*differ from rank 0" -np 1 "${GOOD[@]}" : -np 1 "$P" "$S/cornell.scene" -q \
    --size 40x30 --spp 9 -o "$W/fail.pfm"
t_fails guiding "rank 0: --guiding: guiding cannot be split" -np 2 "${GOOD[@]}" --guiding on
t_fails bad_option "rank 0: .*--spp" -np 2 "${GOOD[@]}" --spp 0

# a rank killed while rendering: the job ends (mpirun says which rank died), no output file
t_killed() {
    local status=0 pid child rank1="" i
    rm -f "$W/killed.pfm"
    "$MPIRUN" "${MPIFLAGS[@]}" -np 2 "$P" "$S/cornell.scene" -q --size 160x120 --spp 100000 --threads 1 \
        -o "$W/killed.pfm" >"$W/killed.out" 2>"$W/killed.err" &
    pid=$!
    for i in $(seq 1 100); do # the rank-1 process among mpirun's children (Open MPI, MPICH env)
        for child in $(pgrep -P "$pid" 2>/dev/null); do
            if tr '\0' '\n' <"/proc/$child/environ" 2>/dev/null | grep -qE '^(OMPI_COMM_WORLD_RANK|PMI_RANK)=1$'; then
                rank1=$child
            fi
        done
        [ -n "$rank1" ] && break
        sleep 0.1
    done
    if [ -z "$rank1" ]; then
        kill "$pid" 2>/dev/null
        wait "$pid" 2>/dev/null
        fail killed_rank "could not find the rank-1 process among mpirun's ($pid) children"
        return
    fi
    sleep 1 # rendering by now
    kill -KILL "$rank1"
    wait "$pid" || status=$?
    if [ $status != 0 ] && [ -z "$(ls "$W" | grep '^killed\.pfm' || true)" ] && grep -q "signal 9" "$W/killed.err"; then
        pass killed_rank "exit status $status, no file: $(grep -m 1 'signal 9' "$W/killed.err" | sed 's/^ *//')"
    else
        fail killed_rank "exit status $status, stderr: '$(head -n 4 "$W/killed.err" | tr '\n' '|')'"
    fi
}
t_killed

echo "$passed passed, $failed failed, 0 skipped"
[ $failed = 0 ]
