#!/usr/bin/env bash
# make faults CLUSTER=1: faults that need the namespace cluster (scripts/cluster/netns.sh: six
# machines, each a network namespace with its own address): the platform is started as by
# `make cluster` (roslaunch <machine> tags from the core PC, recording on the core PC), faults.py's
# probe runs on the core PC, and each fault is judged like the single-host suite (run.sh):
#   console_link_cut   the console PC's link (eth0 of its namespace) down for 2 s, then up
#   machine_gone       the left arm controller: its arm simulator SIGKILLed and its link down for
#                      4 s; its roslaunch child respawns the simulator, which registers again
#                      once the link is back; judged from then on (its first measured pose)
# OUT/faults.md, OUT/events.csv, OUT/*.csv, OUT/launch.log, OUT/platform.bag as run.sh's.
# Exit: 0 every expectation met, 1 one or more violated, 2 the cluster or the platform did not
# start, 77 not root (skipped). Teardown (namespaces, links, processes) always runs.
# Usage: scripts/faults/cluster.sh [OUT]   (CONTROL_RATE, SARAS_NETNS_* as scripts/cluster.sh)
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
OUT="$(realpath -m "${1:-$here/../../out/faults_cluster}")"
if [ "$(id -u)" != 0 ]; then
  echo "faults (cluster): SKIP: root is required (network namespaces, an sshd per machine)" >&2; exit 77
fi
# shellcheck disable=SC1091
source "$here/../env.sh"
# shellcheck disable=SC1091
source "$here/../cluster/run_lib.sh"
mkdir -p "$OUT"; rm -f "$OUT"/*.csv "$OUT"/platform.bag* "$OUT"/faults.md "$OUT"/launch.log
make_run_keys "$OUT/keys" || exit 2
export SARAS_NETNS_RUN="${SARAS_NETNS_RUN:-/tmp/${SARAS_NETNS_PREFIX:-saras}_cluster}"
NETNS=(bash "$here/../cluster/netns.sh")
F="$here/faults.py"
pids=()
teardown() {
  trap '' INT TERM
  local p; for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null; done; sleep 1
  "${NETNS[@]}" down > /dev/null || echo "faults (cluster): teardown incomplete"
  rm -rf "$SARAS_KEY_DIR"
}
trap teardown EXIT
trap 'echo "faults (cluster): interrupted"; exit 130' INT TERM
# shellcheck disable=SC1091
source "$here/lib.sh"   # now, expect, record, note, judge_bags
link() { ip -n "$(eval echo "\$SARAS_NS_$1")" link set eth0 "$2"; }   # link ROLE up|down
ns_pids_of() {  # ROLE PATTERN: processes of ROLE's namespace whose command line matches PATTERN
  local p; for p in $(ip netns pids "$(eval echo "\$SARAS_NS_$1")"); do
    tr '\0' ' ' < "/proc/$p/cmdline" 2>/dev/null | grep -q -- "$2" && echo "$p"; done
}

resource_defaults || exit 2
"${NETNS[@]}" down > /dev/null 2>&1
"${NETNS[@]}" up > "$OUT/netns_up.txt" 2>&1 || { rc=$?; cat "$OUT/netns_up.txt"; exit "$([ "$rc" = 77 ] && echo 77 || echo 2)"; }
# shellcheck disable=SC1091
source "$SARAS_NETNS_RUN/cluster.env"
RECORDING="$(rospack find saras_bringup)/config/recording.yaml"
"${NETNS[@]}" exec core_pc roslaunch -p 11311 "$SARAS_WS/launch/cluster.launch" \
  core_addr:="$SARAS_ADDR_core_pc" teleop_addr:="$SARAS_ADDR_teleop_pc" dvrk_addr:="$SARAS_ADDR_dvrk_pc" \
  console_addr:="$SARAS_ADDR_console_pc" saras_left_addr:="$SARAS_ADDR_saras_left" \
  saras_right_addr:="$SARAS_ADDR_saras_right" sim:=true rviz:=false record:=true bag:="$OUT/platform.bag" \
  control_rate:="$CONTROL_RATE" endoscope_width:="$endo_w" endoscope_height:="$endo_h" > "$OUT/launch.log" 2>&1 &
launch=$!; pids+=("$launch")
sleep 3
if ! "${NETNS[@]}" exec core_pc rosrun saras_bringup wait_ready --config "$RECORDING" --timeout "${READY_TIMEOUT:-240}"; then
  echo "faults (cluster): the platform did not come up; see $OUT/launch.log"; tail -n 20 "$OUT/launch.log"; exit 2
fi
"${NETNS[@]}" exec core_pc python3 "$F" probe "$OUT" > "$OUT/probe.log" 2>&1 & probe=$!; pids=("$probe" "${pids[@]}")
sleep 12   # start-up transients, collision monitoring's grace

expect console_link_cut "console PC link down 2 s, then up: both arms hold <= 50 ms (console STALE), no motion; resume only through the clutch, jump < 1 mm, <= 50 mm/s; STALE on /diagnostics" "hold resume diag"
t0=$(now); link console_pc down; sleep 2; link console_pc up; t1=$(now)
sleep 10; record "$t0" "$t1" 0.05

expect machine_gone "left arm controller gone 4 s (simulator killed, link down), then back (respawned): left chain holds <= 50 ms, collision distance unknown while no pose; resume only through the clutch from the measured pose (< 1 mm, <= 50 mm/s); right arm unaffected; reported" "hold resume right diag unknown"
simpat=saras_simulation/saras_arm_sim; sim="$(ns_pids_of saras_left "$simpat" | head -1)"
t0=$(now); link saras_left down; [ -n "$sim" ] && kill -KILL "$sim" || violations+="no arm simulator found on saras_left;"
sleep 4; link saras_left up; t1=$(now)
# back: the respawned simulator's first measured pose (its start-up takes seconds on a loaded host)
n0="$(wc -l < "$OUT/ee_left.csv")"; back=""
for _ in $(seq 900); do [ "$(wc -l < "$OUT/ee_left.csv")" -gt "$n0" ] && { back=$(now); break; }; sleep 0.1; done
if [ -n "$back" ]; then note "arm simulator back (first measured pose) $(python3 -c "print('+%.1f s' % ($back - $t0))") after the fault"
else violations+="the arm simulator did not come back within 90 s;"; fi
sleep 14; record "$t0" "$t1" 0.05

kill -INT "$probe" 2>/dev/null
stop_pid "$launch" roslaunch "$OUT/platform.bag.active"
judge_bags; exit $?
