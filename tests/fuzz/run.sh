#!/usr/bin/env bash
# Runs one harness for a while on a copy of its seed corpus (the seeds in the source tree stay
# as they are); a crash, a timeout (an input over 10 s) or an out-of-memory (over 2 GB) fails,
# and the input that did it is left in WORK/artifacts/. libFuzzer's own log goes to WORK/log;
# what is printed is its final statistics, or on a failure the report that ended the run and a
# command that replays the input.
# Usage: tests/fuzz/run.sh HARNESS_BINARY SEED_DIR WORK_DIR SECONDS [libFuzzer options…]
# (The ctests pass -seed=1. That does not make a run repeatable: libFuzzer keeps the inputs that
# reach new code, and what a run covers varies a little from run to run (threads, timing), so
# the sequences part. Hence the input is printed: a CI failure replays from its bytes.)
set -uo pipefail
binary=$1 seeds=$2 work=$3 seconds=$4
shift 4
rm -rf "$work/corpus" "$work/artifacts"
mkdir -p "$work/corpus" "$work/artifacts"
cp -R "$seeds/." "$work/corpus/"
"$binary" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/" "$@" "$work/corpus" >"$work/log" 2>&1
status=$?
if [ "$status" -eq 0 ]; then
  grep -a -E '^(INFO: Seed|Done|stat::)' "$work/log"
  exit 0
fi
# The report starts at the sanitizer's or libFuzzer's first line about it.
start=$(grep -a -n -m1 -E '^(==[0-9]+==|terminate called|INFO: libFuzzer|ALARM|SUMMARY)' \
  "$work/log" | cut -d: -f1)
tail -n +"${start:-1}" "$work/log" | cut -c1-400 | head -120
for artifact in "$work"/artifacts/*; do
  [ -e "$artifact" ] || continue
  echo "input ($(wc -c <"$artifact") bytes): $artifact"
  head -c 600 "$artifact" | od -c | head -24
  echo "replay: $binary $artifact"
done
echo "fuzz run failed (exit $status); the whole log: $work/log"
exit "$status"
