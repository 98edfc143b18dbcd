#!/usr/bin/env bash
# Run the whole platform headless in simulation for DURATION seconds and write:
#   OUT/platform.bag            the recording (rosbag of src/saras_bringup/config/recording.yaml) and
#   OUT/platform.teleop.bag     its in-process part (the streams recorded inside /teleop/teleop_manager)
#   OUT/report/index.html       plots, augmented stereo frame, operator view page, rviz screenshot, topic table
#   OUT/bag_check.txt           per-topic counts, rates, sequence/stamp gaps
#   OUT/report/cpu.txt          CPU per process over the recording against its budget
#   OUT/launch.log              everything the nodes printed
# Exit status: 0 when every required stream was recorded at rate without lost messages,
# 1 naming the missing streams otherwise, 2 when the platform could not start.
# Usage: scripts/demo.sh [DURATION] [OUT] [extra roslaunch args, e.g. channel_delay_ms:=200]
# CONTROL_RATE (console stream + teleoperation loop, Hz): default 1000 (D7.2) on machines with at
# least 4 cores; 250 on smaller machines, where ~35 processes cannot all run a 1 kHz loop
# (see README, "Resource budget"). The bag check judges the control streams against this rate.
# ENDOSCOPE_SIZE (rendered stereo endoscope, WIDTHxHEIGHT): default 1280x720 on machines with at least
# 4 cores; 640x360 on smaller ones, where rendering, overlay and JPEG of two 720p eyes at 30 fps take
# about a core and starve the simulators (README, "Resource budget").
# RECORD_IN_PROCESS=0: one bag, every stream over TCP (recorder --no-in-process); default: the
# teleoperation's 1 kHz streams in OUT/platform.teleop.bag, recorded inside /teleop/teleop_manager.
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
DURATION="${1:-30}"; OUT="${2:-$here/../out/demo}"; shift $(( $# >= 2 ? 2 : $# ))
# shellcheck disable=SC1091
source "$here/env.sh"
# shellcheck disable=SC1091
source "$here/cluster/run_lib.sh"
OUT="$(realpath -m "$OUT")"
REPORT="$OUT/report"
mkdir -p "$REPORT"
rm -f "$OUT"/platform.bag "$OUT"/platform.bag.active "$OUT"/platform.*.bag "$OUT"/platform.*.bag.active "$REPORT"/*.png
export ROS_HOME="$OUT/ros_home"; export ROS_LOG_DIR="$ROS_HOME/log"; mkdir -p "$ROS_LOG_DIR"
make_run_keys "$OUT/keys" || exit 2   # throw-away link keys of this run, deleted at exit
port="$(free_port)"
export ROS_MASTER_URI="http://127.0.0.1:$port" ROS_HOSTNAME=127.0.0.1

pids=()
cleanup() {
  for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null; done
  sleep 1
  for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
  rm -rf "$SARAS_KEY_DIR"
}
trap cleanup EXIT
# Virtual display for rviz (software GL); the screenshot shows what a user would see.
display_num=$(( 90 + RANDOM % 100 ))
Xvfb ":$display_num" -screen 0 1600x1000x24 -nolisten tcp >"$OUT/xvfb.log" 2>&1 &
pids+=($!)
export DISPLAY=":$display_num" LIBGL_ALWAYS_SOFTWARE=1
sleep 1

resource_defaults || exit 2
echo "demo: platform for ${DURATION}s, ROS master :$port, display $DISPLAY, output $OUT, control rate ${CONTROL_RATE} Hz, endoscope ${endo_w}x${endo_h}"
view_port="$(free_port)"   # operator view page (saras_operator_view), screenshot after the recording
roslaunch -p "$port" "$SARAS_WS/launch/platform.launch" sim:=true rviz:=false record:=false \
  control_rate:="$CONTROL_RATE" endoscope_width:="$endo_w" endoscope_height:="$endo_h" \
  operator_view_port:="$view_port" "$@" >"$OUT/launch.log" 2>&1 &
launch_pid=$!
pids=("$launch_pid" "${pids[@]}")

# Start-up (35 processes, robot descriptions, renderer set-up) is not part of the measured run:
# record once every required stream is flowing.
sleep 3
if ! rosrun saras_bringup wait_ready --timeout "${READY_TIMEOUT:-180}"; then
  echo "demo: the platform did not come up; last lines of $OUT/launch.log:"; tail -n 30 "$OUT/launch.log"
  exit 2
fi
echo "demo: platform up, recording ${DURATION}s"
recording="$(rospack find saras_bringup)/config/recording.yaml"
# the bags of the recording: platform.bag and its in-process parts (recorder --print-bags)
# RECORD_IN_PROCESS=0: every stream in platform.bag (recorder --no-in-process), for comparison
in_process_flag=(); [[ "${RECORD_IN_PROCESS:-1}" == 0 ]] && in_process_flag=(--no-in-process)
mapfile -t parts < <(rosrun saras_bringup recorder --config "$recording" --output "$OUT/platform.bag" \
  "${in_process_flag[@]}" --print-bags | tail -n +2)
rosrun saras_bringup recorder --config "$recording" --output "$OUT/platform.bag" "${in_process_flag[@]}" \
  __name:=recorder >"$OUT/recorder.log" 2>&1 &
record_pid=$!
pids=("$record_pid" "${pids[@]}")
if ! wait_recording "$record_pid" "$OUT/platform.bag"; then
  echo "demo: the recorder stopped; see $OUT/recorder.log"; exit 2
fi

# CPU of every process over the recording window (two /proc samples, nothing runs in between)
rosrun saras_bringup proc_cpu sample --root "$launch_pid" --root "$record_pid" --out "$OUT/cpu_start.json" \
  || echo "demo: CPU sample failed"
for ((t = 0; t < DURATION; t++)); do
  sleep 1
  if ! kill -0 "$launch_pid" 2>/dev/null; then
    echo "demo: the platform stopped early; last lines of $OUT/launch.log:"; tail -n 30 "$OUT/launch.log"
    exit 2
  fi
done

rosrun saras_bringup proc_cpu sample --root "$launch_pid" --root "$record_pid" --out "$OUT/cpu_end.json" \
  || echo "demo: CPU sample failed"
echo "demo: stopping the recording"
stop_pid "$record_pid" "the recorder" "$OUT/platform.bag.active" "${parts[@]/%/.active}"
for part in "${parts[@]}"; do   # closed by the nodelet manager when it unloads the recorder's nodelet
  wait_closed "$part.active" || echo "demo: $part is still open (reindexed after the platform stops)"
done
# after the recording (a browser costs a core for a few seconds): the operator view page as a browser shows it
echo "demo: operator view page in headless Chromium"
rosrun saras_operator_view page_screenshot "http://127.0.0.1:$view_port/" "$REPORT/operator_view.png" \
  --json "$REPORT/operator_view.json" --timeout 60 >"$OUT/operator_view.log" 2>&1 \
  || echo "demo: the operator view page was not live (see $OUT/operator_view.log)"
# after the recording: querying ~35 nodes over XML-RPC stalls the 2-core host for seconds
echo "demo: capturing the parameters and the node graph"
rosparam dump "$OUT/params.yaml" 2>/dev/null || true
python3 "$here/node_graph.py" "$OUT/node_graph.md" || echo "demo: node graph capture failed"
echo "demo: stopping the platform"
stop_pid "$launch_pid" roslaunch
if ! close_bag "$OUT/platform.bag"; then
  echo "demo: no recording was written ($OUT/platform.bag missing)"; exit 2
fi
extra_bags=()
for part in "${parts[@]}"; do
  if close_bag "$part"; then extra_bags+=("$part"); else echo "demo: no in-process part $part (see $OUT/recorder.log)"; fi
done
# The demo's own measurements read the bag afterwards: nothing but the platform runs while it records.
rosrun saras_visual_feedback visual_feedback_snapshot "$OUT/platform.bag" --output "$REPORT/augmented_stereo" \
  >"$OUT/snapshot.log" 2>&1 || echo "demo: no augmented stereo in the recording (see $OUT/snapshot.log)"
colours="$(python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(d)" "$REPORT/augmented_stereo.json" 2>/dev/null || echo 'no augmented images captured')"
echo "demo: visual feedback: $colours"

# rviz is not run during the recording (software GL would take a core from the 1 kHz loops); the
# screenshot replays the recording into rviz, which also shows that `rosbag play` reproduces the scene.
echo "demo: replaying the recording into rviz for the screenshot"
replay_port="$(free_port)"
ROS_MASTER_URI="http://127.0.0.1:$replay_port" roslaunch -p "$replay_port" saras_bringup replay.launch \
  bag:="$OUT/platform.bag" extra_bags:="${extra_bags[*]}" >"$OUT/replay.log" 2>&1 &
replay_pid=$!
pids=("$replay_pid" "${pids[@]}")
sleep "${RVIZ_WAIT:-20}"
python3 -c "from PIL import ImageGrab; ImageGrab.grab(xdisplay='$DISPLAY').save('$REPORT/rviz.png')" \
  || echo "demo: rviz screenshot failed"
stop_pid "$replay_pid" "the replay"

# Calibration accuracy table (issue: hand-eye vs every OpenCV method, with and without outliers)
echo "demo: hand-eye calibration benchmark (${HANDEYE_TRIALS:-10} trials per scenario)"
TRIALS="${HANDEYE_TRIALS:-10}" bash "$SARAS_WS/src/saras_calibration/bench/run" >"$REPORT/hand_eye_bench.txt" 2>&1 \
  || echo "demo: hand-eye benchmark failed (see $REPORT/hand_eye_bench.txt)"

echo "demo: CPU per process over the recording [% of one core]"
rosrun saras_bringup proc_cpu table "$OUT/cpu_start.json" "$OUT/cpu_end.json" --text "$REPORT/cpu.txt" \
  --json "$REPORT/cpu.json" || echo "demo: no CPU table"
rosrun saras_bringup bag_check "$OUT/platform.bag" --control-rate "$CONTROL_RATE" --json "$REPORT/topics.json" | tee "$OUT/bag_check.txt"
check_rc=${PIPESTATUS[0]}
rosrun saras_bringup make_report "$OUT/platform.bag" "$REPORT" --check "$REPORT/topics.json" \
  --params "$OUT/params.yaml" \
  --extra "Augmented stereo endoscope frame|augmented_stereo.png|/visual_feedback/{left,right}/image (HMD images, recorded as JPEG), last pair of the run; over the run: $colours" \
  --extra "Hand-eye calibration: robust solver vs OpenCV methods|hand_eye_bench.txt|src/saras_calibration/bench/run with TRIALS=${HANDEYE_TRIALS:-10} (README: 100 trials)" \
  --extra "Operator view (browser page, headless Chromium)|operator_view.png|http://127.0.0.1:<operator_view_port>/ served by saras_operator_view during the run, captured after the recording: augmented stereo, tool distances with their colours, tank energies, component health; $(tail -n 1 "$OUT/operator_view.log" 2>/dev/null)" \
  --extra "CPU per process over the recording|cpu.txt|percent of one core between the start and the end of the recording (/proc, saras_bringup proc_cpu), budgets of saras_bringup/config/cpu_budget.yaml (set for 1 kHz and 720p30; this run: $CONTROL_RATE Hz, ${endo_w}x${endo_h})" \
  --extra "rviz (headless, Xvfb)|rviz.png|the recording replayed into rviz (roslaunch saras_bringup replay.launch bag:=... extra_bags:=...), Figure 4 scene" \
  --summary "make demo DURATION=$DURATION CONTROL_RATE=$CONTROL_RATE: simulated platform, $(date -u '+%Y-%m-%d %H:%M UTC')"
echo "demo: report at $REPORT/index.html"
exit "$check_rc"
