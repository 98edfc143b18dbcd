#!/usr/bin/env bash
# Run every package benchmark (src/*/bench/run) and print their tables, then the whole platform at the
# deliverable's nominal rates (scripts/bench_platform.sh: 1 kHz, 1280x720 stereo at 30 Hz, 60 s; CPU of
# every process against its budget and the stream table), so that the teleoperation latencies and the
# CPU figures come from the same `make bench` run. BENCH_PLATFORM=0 skips the platform section.
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
rc=0
for b in "$SARAS_WS"/src/*/bench/run; do
  [ -x "$b" ] || continue
  echo "=== $(basename "$(dirname "$(dirname "$b")")") ==="
  "$b" || { echo "benchmark $b failed"; rc=1; }
done
if [ "${BENCH_PLATFORM:-1}" != "0" ]; then
  echo "=== platform (nominal rates) ==="
  bash "$here/bench_platform.sh" "${PLATFORM_DURATION:-60}" "$SARAS_WS/out/bench_platform" || { echo "platform benchmark failed"; rc=1; }
fi
exit $rc
