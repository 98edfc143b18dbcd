#!/usr/bin/env bash
# `make cluster`: the platform on the six machines of D7.2 Section 2, built on this host out of
# network namespaces (scripts/cluster/netns.sh: own address, sshd and ROS_IP per machine), started
# by roslaunch's <machine> tags from the core PC (launch/cluster.launch). Writes like `make demo`:
#   OUT/cluster.bag           the recording (recorder on the core PC)
#   OUT/bag_check.txt         per-topic counts/rates/gaps, stamp skew per publishing machine
#   OUT/machines.json         node -> machine, topics between machines, console/arm links
#   OUT/report/index.html     a section per machine (nodes, links, stamp skew) + the demo plots
#   OUT/launch.log, OUT/run/  roslaunch output; relay counters, clock monitor capture
# Teardown (every namespace, link and process) runs on exit, failure and Ctrl-C.
# Usage: scripts/cluster.sh [DURATION] [OUT] [extra cluster.launch args]
# Environment:
#   CONTROL_RATE, ENDOSCOPE_SIZE  as scripts/demo.sh
#   IMPAIR_DELAY_MS, IMPAIR_JITTER_MS, IMPAIR_LOSS, IMPAIR_BURST
#                     relays (netem_relay) on the console->teleop UDP link (both directions) and the
#                     teleop->SARAS Socket.IO links: one-way delay/jitter [ms], loss fraction (UDP),
#                     IMPAIR_BURST=1 makes the loss bursty (Gilbert-Elliott, mean burst 4 packets)
#   IMPAIR_ARM_DELAY_MS  one-way delay [ms] of the Socket.IO links alone (default IMPAIR_DELAY_MS)
#   IMPAIR_CHANNEL=1   the same delay, jitter and loss also on the teleoperation's master-slave channel
#                     between the energy tanks (teleop.launch channel_*; the two-layer design's link)
#   BYPASS_TANKS=true  teleoperation without the passivity layer (experiments only)
#   CUT_LINK_AT=S      cut the console link S seconds into the recording by stopping its relay
#                     (needs an IMPAIR_* setting, e.g. IMPAIR_DELAY_MS=0; for the time-to-hold)
#   FAKETIME_MACHINE, FAKETIME   run that (non-core) machine's nodes with its clock shifted by
#                     FAKETIME seconds (libfaketime; e.g. dvrk_pc +0.05)
#   MAX_SKEW_MS, MAX_AHEAD_MS   bag_check's stamp-skew limits per machine (20 ms late, 2 ms ahead)
#   SARAS_NETNS_PREFIX, SARAS_NETNS_SUBNET, SARAS_NETNS_RUN   as scripts/cluster/netns.sh
# Exit: 0 all required streams recorded, 1 problems (named), 2 no start, 77 not root (skipped).
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
DURATION="${1:-30}"; OUT="${2:-$here/../out/cluster}"; shift $(( $# >= 2 ? 2 : $# ))
if [ "$(id -u)" != 0 ]; then
  echo "cluster: SKIP: root is required (network namespaces, an sshd per machine): sudo make cluster" >&2
  exit 77
fi
# shellcheck disable=SC1091
source "$here/env.sh"
# shellcheck disable=SC1091
source "$here/cluster/run_lib.sh"
OUT="$(realpath -m "$OUT")"; REPORT="$OUT/report"; RUNLOG="$OUT/run"
mkdir -p "$REPORT" "$RUNLOG"
make_run_keys "$OUT/keys" || exit 2   # throw-away link keys of this run (deleted at teardown)
rm -f "$OUT"/cluster.bag "$OUT"/cluster.bag.active "$OUT"/cluster.*.bag "$OUT"/cluster.*.bag.active "$REPORT"/*.png "$RUNLOG"/*
export SARAS_NETNS_RUN="${SARAS_NETNS_RUN:-/tmp/${SARAS_NETNS_PREFIX:-saras}_cluster}"
NETNS=(bash "$here/cluster/netns.sh")
BAG="$OUT/cluster.bag"
pids=()

teardown() {
  local p
  trap '' INT TERM  # a second Ctrl-C must not interrupt the teardown
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null; done
  sleep 1
  "${NETNS[@]}" down || echo "cluster: teardown incomplete (see above)"
  rm -rf "$SARAS_KEY_DIR"
}

# in_ns ROLE CMD...: CMD in ROLE's namespace. Started in the background, `"${NETNS[@]}" exec ... &`
# (not this function) so that $! is CMD itself (netns.sh execs it) and stop_pid's SIGINT reaches it.
in_ns() { "${NETNS[@]}" exec "$@"; }

# write_links FILE NAME PROTO LISTEN TARGET [SOURCE]: one netem_relay links file
write_links() {
  local file="$1" burst="" new=0 delay="${IMPAIR_DELAY_MS:-0}"
  [ "$3" = tcp ] && delay="${IMPAIR_ARM_DELAY_MS:-$delay}"
  [ -f "$file" ] || new=1
  if [ "${IMPAIR_BURST:-0}" = 1 ] && [ "$3" = udp ]; then
    # mean loss pi*loss_bad with pi = p_gb/(p_gb+p_bg): p_bg 0.25 (bursts of 4), pi = IMPAIR_LOSS
    burst="$(python3 -c "l=float('${IMPAIR_LOSS:-0.1}'); print('burst: {p_good_bad: %.5f, p_bad_good: 0.25, loss_good: 0.0, loss_bad: 1.0}' % (0.25*l/(1-l)))")"
  fi
  {
    [ "$new" = 1 ] && echo "links:"
    echo "  - name: $2"
    echo "    protocol: $3"
    echo "    listen: $4"
    echo "    target: $5"
    [ -n "${6:-}" ] && echo "    source: $6"
    echo "    delay_ms: $delay"
    echo "    jitter_ms: ${IMPAIR_JITTER_MS:-0}"
    if [ "$3" = udp ]; then
      if [ -n "$burst" ]; then echo "    $burst"; else echo "    loss: ${IMPAIR_LOSS:-0}"; fi
    fi
    echo "    seed: 7"
    echo "    reverse: {delay_ms: $delay, jitter_ms: ${IMPAIR_JITTER_MS:-0}}"
  } >> "$file"
}

# start_relays: relays in the console PC (console state out, force commands in) and in the teleop
# PC (Socket.IO to each arm); sets launch_args to route the links through them.
start_relays() {
  local c="$SARAS_ADDR_console_pc" t="$SARAS_ADDR_teleop_pc"
  rm -f "$RUNLOG/links_console.yaml" "$RUNLOG/links_teleop.yaml"
  write_links "$RUNLOG/links_console.yaml" console_to_teleop udp "$c:16000" "$t:8888" "$c:0"
  write_links "$RUNLOG/links_console.yaml" commands_to_console udp "$c:5006" "$c:5016"
  write_links "$RUNLOG/links_teleop.yaml" teleop_to_saras_left tcp "$t:15001" "$SARAS_ADDR_saras_left:5001"
  write_links "$RUNLOG/links_teleop.yaml" teleop_to_saras_right tcp "$t:15002" "$SARAS_ADDR_saras_right:5002"
  local role
  for role in console teleop; do
    # real-time priority: the emulated network must not add this host's scheduling delays to the link
    "${NETNS[@]}" exec "${role}_pc" chrt -r 10 rosrun saras_bringup netem_relay "$RUNLOG/links_$role.yaml" --period 10 \
      --json "$RUNLOG/relay_$role.json" >"$RUNLOG/relay_$role.log" 2>&1 &
    pids+=($!); eval "relay_${role}_pid=$!"
  done
  if [ "${IMPAIR_CHANNEL:-0}" = 1 ]; then
    launch_args+=(channel_delay_ms:="${IMPAIR_DELAY_MS:-0}" channel_jitter_ms:="${IMPAIR_JITTER_MS:-0}"
                  channel_loss:="${IMPAIR_LOSS:-0}" channel_burst_length:="$([ "${IMPAIR_BURST:-0}" = 1 ] && echo 4 || echo 1)")
    # set-points carry the master's sample time: the drivers' age limit (100 ms) plus the channel's latency
    local age
    age="$(awk -v d="${IMPAIR_DELAY_MS:-0}" -v j="${IMPAIR_JITTER_MS:-0}" 'BEGIN {if (d + j > 0) print 0.1 + 1.5e-3 * (d + j)}')"
    [ -n "$age" ] && launch_args+=(arm_max_target_age:="$age")
  fi
  launch_args+=(console_target:="$c" console_target_port:=16000 console_listen_port:=5016
                left_arm_host:="$t" left_arm_port:=15001 left_arm_serve_port:=5001
                right_arm_host:="$t" right_arm_port:=15002 right_arm_serve_port:=5002)
  sleep 2
}

# record_run: recorder on the core PC for DURATION s; cuts the console link at CUT_LINK_AT. One bag
# with every stream (--no-in-process): the teleoperation's nodelet manager runs on the teleop PC, so
# its streams cannot be recorded inside it by a recorder on the core PC.
record_run() {
  "${NETNS[@]}" exec core_pc rosrun saras_bringup recorder --config "$RECORDING" --output "$BAG" --no-in-process \
    __name:=recorder >"$OUT/recorder.log" 2>&1 &
  local record_pid=$! t
  pids=("$record_pid" "${pids[@]}")
  wait_recording "$record_pid" "$BAG" || { echo "cluster: the recorder stopped; see $OUT/recorder.log"; return 2; }
  echo "cluster: recording ${DURATION}s"
  for ((t = 0; t < DURATION; t++)); do
    if [ -n "${CUT_LINK_AT:-}" ] && [ "$t" = "$CUT_LINK_AT" ] && [ -n "${relay_console_pid:-}" ]; then
      date +%s.%N > "$RUNLOG/link_cut_time"
      kill -TERM "$relay_console_pid"
      echo "cluster: console link cut at t=${t}s (relay stopped)"
    fi
    sleep 1
    kill -0 "$launch_pid" 2>/dev/null || { echo "cluster: roslaunch stopped early"; tail -n 30 "$OUT/launch.log"; return 2; }
  done
  stop_pid "$record_pid" "the recorder" "$BAG.active"
}

# capture: parameters, node -> machine graph, links, the clock monitor's status of every machine
capture() {
  echo "cluster: capturing parameters, machines and clock offsets"
  in_ns core_pc rosparam dump "$OUT/params.yaml" 2>/dev/null || true
  in_ns core_pc python3 "$here/cluster/machine_graph.py" "$SARAS_NETNS_RUN/cluster.env" "$OUT/params.yaml" \
    "$OUT/machines.json" $(ls "$RUNLOG"/links_*.yaml 2>/dev/null) | tee "$RUNLOG/machines.txt"
}

main() {
  resource_defaults || exit 2
  trap teardown EXIT
  trap 'echo "cluster: interrupted"; exit 130' INT TERM
  "${NETNS[@]}" down >/dev/null 2>&1
  "${NETNS[@]}" up > "$RUNLOG/netns_up.txt" 2>&1 || { local rc=$?; cat "$RUNLOG/netns_up.txt"; exit "$rc"; }
  cat "$RUNLOG/netns_up.txt"
  # shellcheck disable=SC1091
  source "$SARAS_NETNS_RUN/cluster.env"
  RECORDING="${RECORDING:-$(rospack find saras_bringup)/config/recording.yaml}"
  launch_args=(core_addr:="$SARAS_ADDR_core_pc" teleop_addr:="$SARAS_ADDR_teleop_pc" dvrk_addr:="$SARAS_ADDR_dvrk_pc"
               console_addr:="$SARAS_ADDR_console_pc" saras_left_addr:="$SARAS_ADDR_saras_left"
               saras_right_addr:="$SARAS_ADDR_saras_right"
               sim:=true rviz:=false record:=false control_rate:="$CONTROL_RATE"
               endoscope_width:="$endo_w" endoscope_height:="$endo_h" bypass_tanks:="${BYPASS_TANKS:-false}")
  [ -n "${FAKETIME_MACHINE:-}" ] && launch_args+=(faketime_machine:="$FAKETIME_MACHINE" faketime:="$FAKETIME")
  if [ -n "${IMPAIR_DELAY_MS:-}${IMPAIR_LOSS:-}${IMPAIR_JITTER_MS:-}" ]; then start_relays; fi
  echo "cluster: roslaunch on core_pc ($SARAS_ADDR_core_pc), ${DURATION}s, control rate $CONTROL_RATE Hz, ${launch_args[*]} $*"
  "${NETNS[@]}" exec core_pc roslaunch -p 11311 "$SARAS_WS/launch/cluster.launch" "${launch_args[@]}" "$@" >"$OUT/launch.log" 2>&1 &
  launch_pid=$!
  pids=("$launch_pid" "${pids[@]}")
  sleep 3
  if ! in_ns core_pc rosrun saras_bringup wait_ready --config "$RECORDING" --timeout "${READY_TIMEOUT:-240}"; then
    echo "cluster: the platform did not come up; last lines of $OUT/launch.log:"; tail -n 30 "$OUT/launch.log"; exit 2
  fi
  record_run || exit 2
  capture
  echo "cluster: stopping the platform"
  stop_pid "$launch_pid" roslaunch
  close_bag "$BAG" || { echo "cluster: no recording was written ($BAG missing)"; exit 2; }
  rosrun saras_bringup bag_check "$BAG" --config "$RECORDING" --control-rate "$CONTROL_RATE" \
    --machines "$OUT/machines.json" --max-skew-ms "${MAX_SKEW_MS:-20}" --max-ahead-ms "${MAX_AHEAD_MS:-2}" \
    --json "$REPORT/topics.json" | tee "$OUT/bag_check.txt"
  local check_rc=${PIPESTATUS[0]}
  rosrun saras_bringup make_report "$BAG" "$REPORT" --check "$REPORT/topics.json" --params "$OUT/params.yaml" \
    --machines "$OUT/machines.json" \
    --summary "make cluster DURATION=$DURATION CONTROL_RATE=$CONTROL_RATE: six machines as network namespaces; ${launch_args[*]} $*"
  echo "cluster: report at $REPORT/index.html"
  exit "$check_rc"
}

main "$@"
