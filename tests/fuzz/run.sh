#!/usr/bin/env bash
# Runs one harness for a while on a copy of its seed corpus (the seeds in the source tree stay
# as they are); a crash, a timeout (an input over 10 s) or an out-of-memory (over 2 GB) fails,
# and the input that did it is left in WORK/artifacts/.
# Usage: tests/fuzz/run.sh HARNESS_BINARY SEED_DIR WORK_DIR SECONDS [libFuzzer options…]
set -euo pipefail
binary=$1 seeds=$2 work=$3 seconds=$4
shift 4
rm -rf "$work/corpus"
mkdir -p "$work/corpus" "$work/artifacts"
cp -R "$seeds/." "$work/corpus/"
exec "$binary" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
  -artifact_prefix="$work/artifacts/" "$@" "$work/corpus"
