#!/bin/sh
# A fuzz campaign of one harness of tests/fuzz/ (docs/fuzzing.md, "The campaign"), on
# demand: builds the harnesses (tests/fuzz/build.sh), then runs HARNESS (fmi, state or
# plan) under libFuzzer for SECONDS in all, in WORKERS processes (default 1; one per core
# to spare) sharing one corpus, $OUT/corpus_HARNESS (seeded with tests/fuzz/corpus/HARNESS;
# libFuzzer reloads it, so each worker picks up what the others add).  Each worker is one
# process (fork mode restarts a process per job and reloads the corpus: it ran the FMI
# harness at 40-100 inputs/s against 300), restarted after a finding, which is kept in
# $OUT/artifacts_HARNESS; each run's log is kept in $OUT/logs_HARNESS/START (START the
# campaign's start, UTC: a later campaign in the same OUT keeps its own).  At the end it
# prints every run's executions, time and last coverage line, the total, and the
# findings; merge what is new into the committed corpus with
#
#   $OUT/fuzz_HARNESS -merge=1 tests/fuzz/corpus/HARNESS $OUT/corpus_HARNESS
#
# usage: tests/fuzz/campaign.sh HARNESS SECONDS [WORKERS]     (OUT, default /tmp/djl-fuzz)
#        e.g. nice -n 15 tests/fuzz/campaign.sh plan 36000 2
set -eu
cd "$(dirname "$0")/../.."
[ $# -eq 2 ] || [ $# -eq 3 ] || { echo "usage: $0 fmi|state|plan SECONDS [WORKERS]" >&2; exit 2; }
H=$1
TOTAL=$2
WORKERS=${3:-1}
case $H in
fmi) LEN=1024 ;;
state) LEN=512 ;;
plan) LEN=256 ;;
*) echo "$0: unknown harness '$H' (fmi, state or plan)" >&2; exit 2 ;;
esac
case $TOTAL in
'' | *[!0-9]*) echo "$0: SECONDS must be a whole number, got '$TOTAL'" >&2; exit 2 ;;
esac
case $WORKERS in
'' | *[!0-9]* | 0) echo "$0: WORKERS must be a whole number >= 1, got '$WORKERS'" >&2; exit 2 ;;
esac
OUT=${OUT:-/tmp/djl-fuzz}
export OUT
tests/fuzz/build.sh
start=$(date +%s)
LOGS="$OUT/logs_$H/$(date -u +%Y%m%d-%H%M%S)"
mkdir -p "$OUT/corpus_$H" "$OUT/artifacts_$H" "$LOGS"
cp -n tests/fuzz/corpus/"$H"/* "$OUT/corpus_$H"/ 2>/dev/null || true

worker() { # worker number: runs until SECONDS have passed since the start
    run=0
    while :; do
        left=$((TOTAL - ($(date +%s) - start)))
        [ "$left" -gt 10 ] || break
        run=$((run + 1))
        log="$LOGS/run_w$1_$run.log"
        echo "campaign $H: worker $1, run $run, $left s left" >&2
        "$OUT/fuzz_$H" -max_len=$LEN -len_control=0 -timeout=20 -rss_limit_mb=2048 \
            -max_total_time="$left" -print_final_stats=1 -artifact_prefix="$OUT/artifacts_$H/" \
            "$OUT/corpus_$H" > "$log" 2>&1 || true
    done
}

w=1
while [ "$w" -le "$WORKERS" ]; do
    worker "$w" &
    w=$((w + 1))
done
wait
total=0
for log in "$LOGS"/run_*.log; do
    n=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")
    # a run stopped from outside prints no final stats: its last progress line counts
    [ -n "$n" ] || n=$(grep -E '^#[0-9]+' "$log" | tail -1 | sed 's/^#\([0-9]*\).*/\1/')
    rate=$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")
    last=$(grep -E '^#[0-9]+' "$log" | tail -1 | cut -c1-100)
    found=$(grep -m1 -E 'invariant broken|runtime error|ERROR: AddressSanitizer|ERROR: libFuzzer' "$log" || true)
    echo "$(basename "$log"): ${n:-?} executions, ${rate:-?}/s; $last${found:+; FOUND: $found}"
    total=$((total + ${n:-0}))
done
echo "campaign $H: $total executions in $(($(date +%s) - start)) s; logs in $LOGS; findings in $OUT/artifacts_$H:"
ls "$OUT/artifacts_$H"
