#!/usr/bin/env bash
# `make cluster-impaired`: the teleoperation across the cluster (scripts/cluster.sh) with the console
# UDP link (both directions) and the Socket.IO links to the SARAS arms impaired by netem_relay, with
# the energy tanks on and bypassed. Per case: energy delivered to the operator and the tissue vs
# energy that entered (from the recorded port variables: saras_bringup teleop_energy), tracking
# error, time-to-hold after the console link is cut (CUT_AFTER s before the end). Writes
#   OUT/<case>/...            the cluster run (bag, bag_check, report per machine)
#   OUT/<case>/energy.json, energy.png
#   OUT/index.html, OUT/table.md   the table of every case and the plots
# Usage: scripts/cluster_impaired.sh [DURATION (40)] [OUT] [CASE ...]
# Cases: <link>-<tanks>, link one of d0 d50 d200 (one-way delay, ms), loss10 (10 % random loss),
# burst10 (10 % bursty loss, mean burst 4 packets); tanks one of tanks bypass. Default: all 10.
# Root is required (exit 77 otherwise).
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
DURATION="${1:-40}"; OUT="${2:-$here/../out/cluster_impaired}"; shift $(( $# >= 2 ? 2 : $# ))
CASES=("$@")
if [ ${#CASES[@]} = 0 ]; then
  for l in d0 d50 d200 loss10 burst10; do CASES+=("$l-tanks" "$l-bypass"); done
fi
if [ "$(id -u)" != 0 ]; then
  echo "cluster_impaired: SKIP: root is required (network namespaces): sudo make cluster-impaired" >&2
  exit 77
fi
# shellcheck disable=SC1091
source "$here/env.sh"
OUT="$(realpath -m "$OUT")"
mkdir -p "$OUT"
CUT_AFTER="${CUT_AFTER:-6}"

# recording.yaml + the port variables of both channels
RECORDING="$OUT/recording_energy.yaml"
cp "$(rospack find saras_bringup)/config/recording.yaml" "$RECORDING"
for s in left right; do
  for t in tank_wrench master_twist tank_twist; do
    echo "  - {topic: /teleop/$s/$t, rate: control, group: teleoperation ports, required: false}" >> "$RECORDING"
  done
  echo "  - {topic: /mesa_$s/hold, rate: 0, group: teleoperation ports, required: false}" >> "$RECORDING"
done

# case_env LINK: the IMPAIR_* settings of a link condition. The condition applies to the console link
# and to the teleoperation's master-slave channel between the tanks (IMPAIR_CHANNEL); the Socket.IO
# links to the arm controllers are relayed without delay (ARM_DELAY_MS): the controllers refuse
# set-points older than max_target_age (100 ms), so a longer robot link holds the arms by design.
case_env() {
  local base="IMPAIR_CHANNEL=1 IMPAIR_ARM_DELAY_MS=${ARM_DELAY_MS:-0}"
  case "$1" in
    d0) echo "$base IMPAIR_DELAY_MS=0" ;;
    d50) echo "$base IMPAIR_DELAY_MS=50" ;;
    d200) echo "$base IMPAIR_DELAY_MS=200" ;;
    loss10) echo "$base IMPAIR_DELAY_MS=0 IMPAIR_LOSS=0.1" ;;
    burst10) echo "$base IMPAIR_DELAY_MS=0 IMPAIR_LOSS=0.1 IMPAIR_BURST=1" ;;
    *) return 1 ;;
  esac
}

run_case() {  # run_case NAME
  local name="$1" link="${1%-*}" tanks="${1##*-}" settings bypass=false dir="$OUT/$1"
  settings="$(case_env "$link")" || { echo "cluster_impaired: unknown case $name"; return 2; }
  case "$tanks" in tanks) ;; bypass) bypass=true ;; *) echo "cluster_impaired: unknown case $name"; return 2 ;; esac
  echo "=== $name: $settings BYPASS_TANKS=$bypass"
  # shellcheck disable=SC2086
  env $settings BYPASS_TANKS="$bypass" RECORDING="$RECORDING" CUT_LINK_AT=$((DURATION - CUT_AFTER)) \
    bash "$here/cluster.sh" "$DURATION" "$dir" > "$OUT/$name.log" 2>&1
  local rc=$?
  echo "cluster.sh exit $rc" >> "$OUT/$name.log"
  [ -f "$dir/cluster.bag" ] || { echo "$name: no recording (exit $rc), see $OUT/$name.log"; return 1; }
  local cut=() flags=()
  [ -f "$dir/run/link_cut_time" ] && cut=(--link-cut "$(cat "$dir/run/link_cut_time")")
  [ "$bypass" = true ] && flags=(--bypass)
  rosrun saras_bringup teleop_energy "$dir/cluster.bag" --params "$dir/params.yaml" "${flags[@]}" "${cut[@]}" \
    --json "$dir/energy.json" --plot "$OUT/$name.png" --title "$name: $settings, tanks $tanks" >/dev/null \
    || echo "$name: energy analysis failed"
  python3 -c "import json,sys; d=json.load(open(sys.argv[1])); d.update(case=sys.argv[2], settings=sys.argv[3], exit=int(sys.argv[4])); json.dump(d, open(sys.argv[1], 'w'))" \
    "$dir/energy.json" "$name" "$settings" "$rc" 2>/dev/null
}

for c in "${CASES[@]}"; do run_case "$c"; done
python3 "$here/cluster/impaired_table.py" "$OUT" "${CASES[@]}"
