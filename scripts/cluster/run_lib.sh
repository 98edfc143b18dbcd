# Shell functions shared by scripts/demo.sh and scripts/cluster.sh (source it).

# free_port: an unused TCP port on 127.0.0.1
free_port() {
  python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# file_sizes FILE...: total size of those FILEs that exist [bytes]
file_sizes() {
  local f size=0
  for f in "$@"; do size=$((size + $(stat -c %s "$f" 2>/dev/null || echo 0))); done
  echo "$size"
}

# while_writing TEST [FILE ...]: sleep while the command TEST (eval) succeeds, up to 20 s, a count that
# restarts whenever the FILEs' total size grows, and 240 s in all.
while_writing() {
  local test="$1" last=-1 size t=0 total=0
  shift
  while [ "$t" -lt 40 ] && [ "$total" -lt 480 ] && eval "$test"; do
    total=$((total + 1))
    size=$(file_sizes "$@")
    if [ "$size" -ne "$last" ]; then last=$size; t=0; fi
    sleep 0.5; t=$((t + 1))
  done
}

# stop_pid PID NAME [FILE ...]: SIGINT (roslaunch shuts its nodes down), up to 20 s, then SIGTERM and
# SIGKILL to it and its children (a killed roslaunch would leave its nodes running). With FILEs, the
# 20 s count restarts whenever they grow: the recorder, after SIGINT, writes what it has queued
# (up to buffer_mb of recording.yaml, per bag), which on an overloaded host can take longer than 20 s;
# killing it then would lose the queued end of the recording; a process still writing after 240 s is stopped.
stop_pid() {
  local pid="$1" name="$2"
  shift 2
  kill -INT "$pid" 2>/dev/null
  while_writing "kill -0 $pid 2>/dev/null" "$@"
  if kill -0 "$pid" 2>/dev/null; then
    echo "$name did not stop, terminating it and its children"
    pkill -TERM -P "$pid" 2>/dev/null; kill -TERM "$pid" 2>/dev/null; sleep 2
    pkill -KILL -P "$pid" 2>/dev/null; kill -KILL "$pid" 2>/dev/null
  fi
  wait "$pid" 2>/dev/null
}

# wait_closed FILE: until FILE (a bag being written, .active) is gone, with stop_pid's limits (a part
# bag written inside a nodelet manager is closed and renamed when the manager unloads the nodelet);
# 1 if it is still there.
wait_closed() {
  while_writing "[ -e $(printf %q "$1") ]" "$1"
  [ ! -e "$1" ]
}

# wait_recording PID BAG: until the recorder PID opened BAG.active (0) or stopped (1). The
# recorder's start-up (two rosruns, Python, 38 subscriptions) takes 5-15 s on a loaded 2-core host;
# bag_recorder opens BAG.active, then subscribes (its log is block-buffered, so the file is the signal).
wait_recording() {
  local t
  for ((t = 0; t < 300; t++)); do
    [ -e "$2.active" ] && { sleep 1; return 0; }
    kill -0 "$1" 2>/dev/null || return 1
    sleep 0.2
  done
  return 1
}

# close_bag BAG: reindex BAG.active into BAG when the recorder could not close it; 1 if no bag
close_bag() {
  if [ -f "$1.active" ] && [ ! -f "$1" ]; then
    echo "bag was not closed cleanly, reindexing"
    rosbag reindex "$1.active" >/dev/null && mv "$1.active" "$1"
  fi
  [ -f "$1" ]
}

# resource_defaults: CONTROL_RATE (console stream + teleoperation loop, Hz) and ENDOSCOPE_SIZE
# (WIDTHxHEIGHT) default to the D7.2 values (1000 Hz, 1280x720) on machines with at least 4 cores
# and to 250 Hz, 640x360 on smaller ones (README, "Resource budget"); sets endo_w, endo_h.
# Returns 1 when ENDOSCOPE_SIZE is malformed.
resource_defaults() {
  if [ -z "${CONTROL_RATE:-}" ]; then
    if [ "$(nproc)" -ge 4 ]; then CONTROL_RATE=1000; else CONTROL_RATE=250; fi
  fi
  if [ -z "${ENDOSCOPE_SIZE:-}" ]; then
    if [ "$(nproc)" -ge 4 ]; then ENDOSCOPE_SIZE=1280x720; else ENDOSCOPE_SIZE=640x360; fi
  fi
  if ! [[ "$ENDOSCOPE_SIZE" =~ ^([0-9]+)x([0-9]+)$ ]]; then
    echo "ENDOSCOPE_SIZE must be WIDTHxHEIGHT (e.g. 1280x720), got '$ENDOSCOPE_SIZE'" >&2; return 1
  fi
  endo_w="${BASH_REMATCH[1]}"; endo_h="${BASH_REMATCH[2]}"
}

# make_run_keys DIR: throw-away keys of the authenticated console and arm links for one run
# (docs/security.md): mode 0600 in a 0700 directory; exported as SARAS_KEY_DIR, which the launch
# files read. The caller deletes DIR at exit.
make_run_keys() {
  export SARAS_KEY_DIR="$1"
  rm -rf "$SARAS_KEY_DIR"
  (umask 077 && mkdir -p "$SARAS_KEY_DIR") || return 1
  local key
  for key in console saras_arm; do
    python3 -m saras_drivers.keys "$SARAS_KEY_DIR/$key.key" || { echo "cannot create $SARAS_KEY_DIR/$key.key" >&2; return 1; }
  done
}
