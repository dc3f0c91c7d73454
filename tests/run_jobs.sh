#!/usr/bin/env bash
# run_jobs.sh - runs the test runners of `make test` side by side and adds up their results.
#
#   tests/run_jobs.sh JOBS LOGDIR NAME COMMAND [NAME COMMAND]...
#
# Runs each COMMAND (with bash -c) in the listed order, at most JOBS at a time, each one's output
# into LOGDIR/NAME.log. List the longest first: the pool then ends with short jobs and both cores
# stay busy. When all have ended, prints every log in the listed order under a "==== NAME" line,
# a table of the jobs, and as the last line the sum of the jobs' own last lines,
# "N passed, M failed, K skipped". A job that exits non-zero, or whose last line is not such a
# summary, counts as one failure. Exit status 0 iff nothing failed.
set -u

if [ $# -lt 4 ] || [ $(( ($# - 2) % 2 )) != 0 ]; then
    echo "usage: $0 JOBS LOGDIR NAME COMMAND [NAME COMMAND]..." >&2
    exit 2
fi
jobs_max=$1
logdir=$2
shift 2
case $jobs_max in '' | *[!0-9]* | 0) echo "$0: JOBS must be a positive integer, not '$jobs_max'" >&2; exit 2 ;; esac
mkdir -p "$logdir" || exit 2

names=()
cmds=()
while [ $# -gt 0 ]; do
    case $1 in '' | *[!A-Za-z0-9_.-]*) echo "$0: bad job name '$1'" >&2; exit 2 ;; esac
    names+=("$1")
    cmds+=("$2")
    rm -f "$logdir/$1.log" "$logdir/$1.rc" "$logdir/$1.time"
    shift 2
done

# one job: its output to NAME.log, its exit status and wall time beside it
run_one() {
    local name=$1 cmd=$2 t0=$SECONDS rc=0
    bash -c "$cmd" > "$logdir/$name.log" 2>&1 < /dev/null || rc=$?
    echo "$(( SECONDS - t0 ))" > "$logdir/$name.time"
    echo "$rc" > "$logdir/$name.rc"
}

running=0
for i in "${!names[@]}"; do
    if [ "$running" -ge "$jobs_max" ]; then
        wait -n
        running=$((running - 1))
    fi
    run_one "${names[$i]}" "${cmds[$i]}" &
    running=$((running + 1))
done
wait

summary='^([0-9]+) passed, ([0-9]+) failed, ([0-9]+) skipped$'
passed=0 failed=0 skipped=0 table=()
for i in "${!names[@]}"; do
    name=${names[$i]}
    echo "==== $name: ${cmds[$i]}"
    cat "$logdir/$name.log"
    rc=$(cat "$logdir/$name.rc" 2>/dev/null || echo 1)
    last=$(tail -n 1 "$logdir/$name.log")
    if [[ $last =~ $summary ]]; then
        passed=$((passed + BASH_REMATCH[1]))
        failed=$((failed + BASH_REMATCH[2]))
        skipped=$((skipped + BASH_REMATCH[3]))
        [ "$rc" = 0 ] || [ "${BASH_REMATCH[2]}" != 0 ] || failed=$((failed + 1))
        result=$last
    else
        failed=$((failed + 1))
        result="FAIL: exit status $rc and no summary line"
    fi
    table+=("$(printf '%-22s %5s s  %s' "$name" "$(cat "$logdir/$name.time" 2>/dev/null)" "$result")")
done
echo "==== the jobs ($jobs_max at a time)"
printf '%s\n' "${table[@]}"
echo "$passed passed, $failed failed, $skipped skipped"
[ "$failed" = 0 ]
