#!/usr/bin/env bash
# `make bench-platform`: the whole simulated platform at the deliverable's nominal rates (1 kHz console
# stream and teleoperation, 1280x720 stereo at 30 Hz) for DURATION s (60), through scripts/demo.sh;
# prints the CPU of every process over the recording against saras_bringup/config/cpu_budget.yaml and
# the stream table of bag_check. Exit status: demo.sh's (0 = every required stream at rate, no loss).
# Usage: scripts/bench_platform.sh [DURATION] [OUT]   (CONTROL_RATE / ENDOSCOPE_SIZE override the rates)
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
DURATION="${1:-60}"; OUT="${2:-$here/../out/bench_platform}"
mkdir -p "$OUT"
export CONTROL_RATE="${CONTROL_RATE:-1000}" ENDOSCOPE_SIZE="${ENDOSCOPE_SIZE:-1280x720}"
echo "=== platform at ${CONTROL_RATE} Hz, ${ENDOSCOPE_SIZE} stereo, ${DURATION} s ($(nproc) cores) ==="
bash "$here/demo.sh" "$DURATION" "$OUT" > "$OUT/demo.log" 2>&1
rc=$?
echo "--- CPU per process over the recording [% of one core] ---"
cat "$OUT/report/cpu.txt" 2>/dev/null || echo "(no CPU table; see $OUT/demo.log)"
echo "--- streams (bag_check) ---"
cat "$OUT/bag_check.txt" 2>/dev/null || echo "(no bag check; see $OUT/demo.log)"
echo "platform benchmark: demo exit $rc, report $OUT/report/index.html"
exit $rc
