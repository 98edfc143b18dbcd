# Shell functions shared by scripts/demo.sh and scripts/cluster.sh (source it).

# free_port: an unused TCP port on 127.0.0.1
free_port() {
  python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])'
}

# stop_pid PID NAME [FILE]: SIGINT (roslaunch shuts its nodes down), up to 20 s, then SIGTERM and
# SIGKILL to it and its children (a killed roslaunch would leave its nodes running). With FILE, the
# 20 s count restarts whenever FILE grows: the recorder, after SIGINT, writes what it has queued
# (up to buffer_mb of recording.yaml), which on an overloaded host can take longer than 20 s; killing
# it then would lose the queued end of the recording; a process still writing after 240 s is stopped.
stop_pid() {
  local last=-1 size t=0 total=0
  kill -INT "$1" 2>/dev/null
  while [ "$t" -lt 40 ] && [ "$total" -lt 480 ] && kill -0 "$1" 2>/dev/null; do
    total=$((total + 1))
    if [ -n "${3:-}" ]; then
      size=$(stat -c %s "$3" 2>/dev/null || echo 0)
      if [ "$size" -ne "$last" ]; then last=$size; t=0; fi
    fi
    sleep 0.5; t=$((t + 1))
  done
  if kill -0 "$1" 2>/dev/null; then
    echo "$2 did not stop, terminating it and its children"
    pkill -TERM -P "$1" 2>/dev/null; kill -TERM "$1" 2>/dev/null; sleep 2
    pkill -KILL -P "$1" 2>/dev/null; kill -KILL "$1" 2>/dev/null
  fi
  wait "$1" 2>/dev/null
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
