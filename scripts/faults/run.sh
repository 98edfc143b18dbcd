#!/usr/bin/env bash
# make faults: the platform in simulation on this host, one fault after the other, each judged
# against the outcome stated (printed) before it is injected, from what faults.py's probe recorded
# (set-points, measured poses, collision distances, /diagnostics) and the simulators' logs.
#   OUT/faults.md   the table (also on stdout)       OUT/events.csv  fault times and expectations
#   OUT/*.csv       probe recordings                 OUT/launch.log  everything the nodes printed
#   OUT/platform.bag  the platform's recording (judged with rosbag info at the end)
# Exit status: 0 every expectation met, 1 one or more violated, 2 the platform could not start.
# Usage: scripts/faults/run.sh [OUT]   (CONTROL_RATE, default 250 Hz on < 4 cores)
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
OUT="$(realpath -m "${1:-$here/../../out/faults}")"
# shellcheck disable=SC1091
source "$here/../env.sh"
# shellcheck disable=SC1091
source "$here/../cluster/run_lib.sh"
mkdir -p "$OUT"; rm -f "$OUT"/*.csv "$OUT"/platform*.bag* "$OUT"/faults.md "$OUT"/launch*.log
export ROS_HOME="$OUT/ros_home" ROS_LOG_DIR="$OUT/ros_home/log"; mkdir -p "$ROS_LOG_DIR"
make_run_keys "$OUT/keys" || exit 2   # throw-away link keys of this run, deleted at exit
port="$(free_port)"
export ROS_MASTER_URI="http://127.0.0.1:$port" ROS_HOSTNAME=127.0.0.1
rate="${CONTROL_RATE:-$([ "$(nproc)" -ge 4 ] && echo 1000 || echo 250)}"
F="$here/faults.py"
pids=()
cleanup() { for p in "${pids[@]}"; do kill -INT "$p" 2>/dev/null; done; sleep 2
            for p in "${pids[@]}"; do kill -TERM "$p" 2>/dev/null; done
            rm -rf "$SARAS_KEY_DIR"
            [ -n "${tiny:-}" ] && { umount -l "$tiny" 2>/dev/null; rmdir "$tiny" 2>/dev/null; }; }
trap cleanup EXIT
# shellcheck disable=SC1091
source "$here/lib.sh"   # now, expect, record, note, judge_bags
pid_of() { python3 "$F" pid "$1" 2>/dev/null; }

# the master runs outside roslaunch (a roslaunch-started master would take the platform down with it)
rosmaster --core -p "$port" > "$OUT/master.log" 2>&1 & master=$!; pids+=("$master")
for _ in $(seq 50); do rosparam list >/dev/null 2>&1 && break; sleep 0.2; done
start_platform() {  # LOG: roslaunch the platform on this master, wait for the set-points
  # one bag: manager_kill SIGKILLs the teleop manager, which would take the in-process part's index with it
  roslaunch -p "$port" "$SARAS_WS/launch/platform.launch" sim:=true rviz:=false record:=true operator_view:=false \
    record_in_process:=false \
    bag:="$OUT/platform$1.bag" control_rate:="$rate" endoscope_width:=640 endoscope_height:=360 \
    > "$OUT/launch$1.log" 2>&1 & launch=$!; pids+=("$launch")
  if ! timeout 120 rostopic echo -n 1 /mesa_left/target_pose > /dev/null 2>&1; then
    echo "faults: the platform did not start (see $OUT/launch$1.log)"; exit 2; fi
  sleep 12   # start-up transients, collision monitoring's grace
}
# back LOGFILE PATTERN COUNT TIMEOUT: time when PATTERN appears more than COUNT times in LOGFILE
back() { local t=0; while [ "$t" -lt $(( $4 * 10 )) ]; do
    [ "$(grep -ac "$2" "$1")" -gt "$3" ] && { now; return; }; sleep 0.1; t=$((t + 1)); done; }
kill_respawning() {  # NODE LOG_LINE WHAT: SIGKILL a respawning node; t0 = the kill, t1 = its next LOG_LINE
  local n p; n="$(grep -ac "$2" "$OUT/launch.log")"; p="$(pid_of "$1")"
  t0=$(now); kill -KILL "$p"; t1="$(back "$OUT/launch.log" "$2" "$n" 60)"
  [ -z "$t1" ] && { violations="$3 not respawned"; t1=$(now); }
}
# the probe is also the operator: it presses the clutch of both devices every 4 s (resume after a hold)
python3 "$F" probe "$OUT" > "$OUT/probe.log" 2>&1 & probe=$!; pids+=("$probe")
start_platform ""

expect console_stale "console stopped 1.5 s: both arms hold <= 50 ms, no motion; resume through the clutch, jump < 1 mm, <= 50 mm/s; STALE/ERROR on /diagnostics" "hold resume diag"
p="$(pid_of /touchball_console_sim)"; t0=$(now); kill -STOP "$p"; sleep 1.5; kill -CONT "$p"; t1=$(now)
sleep 8; record "$t0" "$t1" 0.05

expect driver_kill "left driver killed (respawns): left arm holds <= 50 ms, no motion; resume through the clutch from the held pose, jump < 1 mm, <= 50 mm/s; right arm unaffected; reported" "hold resume right diag"
kill_respawning /mesa_left/saras_arms_driver 'connected to http://127.0.0.1:5001' driver
sleep 9; record "$t0" "$t1" 0.05

expect contact_force_spoof "1e6 N on /mesa_left/contact_force for 3 s: left arm holds, no motion; then follows again without a jump; right arm unaffected; reported" "hold resume right diag"
FAULTS_SPOOF_TIMES="$OUT/spoof.txt" python3 "$F" spoof-force left 3.0 > /dev/null 2>&1; read -r t0 t1 < "$OUT/spoof.txt"
sleep 3; record "$t0" "$t1" 0.1

expect zero_stamp_target_spoof "zero-stamp targets 2 cm deeper at 500 Hz for 2 s: rejected by the driver, the arm stays with the real set-point (< 4 mm); right arm unaffected; reported" "spoof right diag"
FAULTS_SPOOF_TIMES="$OUT/spoof.txt" python3 "$F" spoof-target left 2.0 > /dev/null 2>&1; read -r t0 t1 < "$OUT/spoof.txt"
sleep 2; record "$t0" "$t1" 0.05

# console packets (loopback, no key): 1 s of the console's real, accepted state packets captured first
P="$here/packets.py"; cport=8888
python3 "$P" capture "$cport" 1.0 "$OUT/captured.bin" > "$OUT/captured.txt" 2>&1 || echo "   (no console packets captured)"
echo "fault,sent" > "$OUT/sent.csv"
# hostile KIND SECONDS RATE: send, then judge the receiver's survival (same process, no respawn)
hostile() {
  local before_r before_m out; before_r="$(pid_of /touchball_receiver)"; before_m="$(pid_of /teleop/teleop_manager)"
  out="$(python3 "$P" "$1" "$cport" "$2" "$3" "$OUT/captured.bin" 2>> "$OUT/packets.log")"
  read -r t0 t1 sent <<< "${out:-0 0 0}"; [ "$t0" = 0 ] && { t0=$(now); t1=$t0; violations+="nothing sent;"; }
  echo "$name,$sent" >> "$OUT/sent.csv"
  sleep 3
  [ -n "$before_r" ] && [ "$(pid_of /touchball_receiver)" = "$before_r" ] && [ "$(pid_of /teleop/teleop_manager)" = "$before_m" ] \
    || violations+="the receiver (or its manager) restarted;"
  record "$t0" "$t1" 0.05
}
expect console_malformed "2 s of malformed datagrams at twice the console rate (random, short, wrong magic/version/type/size, bad or foreign tags): every one rejected and counted on /diagnostics, the real stream keeps its rate, no hold, no set-point jump, the receiver keeps running" "packets"
hostile malformed 2.0 $((2 * rate))

expect console_replay "2 s of the captured (valid) console packets re-sent at the console rate: rejected by the sequence check (duplicate/out_of_order), counted; real stream keeps its rate, no hold, no jump, receiver keeps running" "packets"
hostile replay 2.0 "$rate"

expect console_flood "3 s of replayed + malformed datagrams at 10x the console rate: counted as rejected (the socket may drop some), the real stream keeps its rate (or holds <= 50 ms), no set-point jump, the receiver keeps running" "packets"
hostile flood 3.0 $((10 * rate))

expect arm_sim_kill "left arm simulator killed (respawns at its initial pose): collision distance of the left tool unknown (NaN) while no pose, teleoperation holds; resume only through the clutch, from the measured pose (< 1 mm); right arm unaffected; reported" "resume right diag unknown"
kill_respawning /mesa_left/saras_arm_sim 'saras_arm_sim: mesa_left on' "arm simulator"
sleep 10; record "$t0" "$t1" 0.05

expect disk_full "a second recorder on an 8 MB disk: stops writing naming the disk, closes an indexed bag, counts what it lost" "none"
tiny="$(mktemp -d /tmp/faults_disk.XXXXXX)"; mount -t tmpfs -o size=8m tmpfs "$tiny"
t0=$(now); timeout 60 rosrun saras_bringup bag_recorder -O "$tiny/full.bag" --min-free 1 --duration 15 \
  /endoscope/left/image_raw/compressed /endoscope/right/image_raw/compressed /mesa_left/ee_pose __name:=faults_disk \
  > "$OUT/disk_full.log" 2>&1; t1=$(now)
grep -q "disk fault on $tiny (tmpfs)" "$OUT/disk_full.log" "$ROS_LOG_DIR"/*faults_disk*.log 2>/dev/null \
  || grep -rq "disk fault on $tiny" "$ROS_LOG_DIR" || violations+="no disk-fault message naming $tiny;"
rosbag info "$tiny/full.bag" > "$OUT/disk_full_baginfo.txt" 2>&1 || violations+="bag not readable/indexed;"
grep -q "lost after the disk fault" "$OUT/disk_full.log" || violations+="losses not reported;"
umount -l "$tiny"; rmdir "$tiny"; tiny=""
record "$t0" "$t1"

expect collision_kill "collision monitoring killed: reported on /diagnostics, set-point speed <= 20 % of 50 mm/s; right arm unaffected" "slow right diag"
p="$(pid_of /colliding_regions)"; t0=$(now); kill -KILL "$p"; sleep 6; t1=$(now); record "$t0" "$t1"

expect manager_kill "teleop manager killed (respawns with its nodelets): both arms hold <= 50 ms (the drivers see the set-point publisher disconnect), no motion; tanks resume with at most the energy they had (journal); resume only through the clutch, jump < 1 mm; the platform keeps running" "hold resume diag tanks"
# back: the respawned receiver reports again on /diagnostics (its nodelets restart with it)
p="$(pid_of /teleop/teleop_manager)"; t0=$(now); kill -KILL "$p"
t1="$(python3 "$F" wait-link-restart "$OUT" "$t0" 90)" || { violations+="the receiver not back within 90 s;"; t1=$(now); }
note "receiver back on /diagnostics $(python3 -c "print('+%.1f s' % ($t1 - $t0))") after the kill"
kill -0 "$launch" 2>/dev/null || violations+="the platform shut down (a required node died with the manager);"
sleep 12; record "$t0" "$t1" 0.05
if ! kill -0 "$launch" 2>/dev/null; then echo "   (platform shut down: started again for the next fault)"; start_platform _2; fi

expect master_kill "ROS master killed: the drivers detect it (refused: at once; polled every 0.2 s), send the protocol hold and stop forwarding (arms hold <= 0.3 s, no motion), the recorder closes an indexed bag, clear errors" "hold"
t0=$(now); kill -KILL "$master"; sleep 8; t1=$(now)
last_bag="$(ls -t "$OUT"/platform*.bag* | head -1)"
[[ "$last_bag" == *.bag ]] || violations+="$(basename "$last_bag") not closed after the master loss;"
grep -q "SAFE STOP" "$OUT"/launch*.log || violations+="no safe-stop message from the drivers;"
logged_after() { local t; t="$(grep -ah "$1" "$OUT"/launch*.log | grep -o '\] \[[0-9.]*\]' | grep -o '[0-9.][0-9.]*' | head -1)"
                 [ -n "$t" ] && python3 -c "print('+%.1f s' % ($t - $t0))" || echo never; }
note "SAFE STOP logged by $(grep -ac "SAFE STOP" "$OUT"/launch*.log | awk -F: '{s+=$NF} END {print s+0}') driver(s), first $(logged_after "SAFE STOP"); recorder closed the bag $(logged_after "closing the bag"); $(basename "$last_bag") $(rosbag info "$last_bag" > /dev/null 2>&1 && echo indexed || echo "NOT indexed")"
record "$t0" "$t1" 0.3

kill -INT "$probe" 2>/dev/null; kill -INT "$launch" 2>/dev/null; sleep 5
judge_bags; exit $?
