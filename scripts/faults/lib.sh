# Shared by the fault suites (run.sh on one host, cluster.sh in the namespace cluster); sourced with
# OUT and F (faults.py) set. Each fault: `expect NAME "TEXT" CHECKS` states the expectation before
# the fault is injected, `record T_FAULT T_BACK [HOLD_LIMIT]` files it in OUT/events.csv with the
# violations found while it ran, `note TEXT` adds a measured outcome shown with its verdict.
now() { python3 -c 'import time; print("%.6f" % time.time())'; }
expect() { name="$1"; text="$2"; checks="$3"; violations=""; echo; echo "== $name"; echo "   EXPECTED: $text"; }
record() { echo "$name,\"$text\",$checks,$1,$2,${3:-0.05},\"$violations\"" >> "$OUT/events.csv"; }
note() { echo "$name,\"$1\"" >> "$OUT/notes.csv"; }
echo "fault,expected,checks,t_fault,t_back,hold_limit,violations" > "$OUT/events.csv"

# judge_bags: rosbag info of every OUT/platform*.bag, faults.py's table, the bags' state appended;
# returns the exit status (1 when an expectation was violated or a bag is unreadable/unindexed)
judge_bags() {
  local b bag="" rc
  for b in "$OUT"/platform*.bag; do
    if rosbag info "$b" > "$b.info.txt" 2>&1; then bag+="$(basename "$b") readable ($(grep -m1 '^messages' "$b.info.txt" | tr -s ' ')); "
    else bag+="$(basename "$b") NOT readable; "; fi
  done
  ls "$OUT"/*.bag.active > /dev/null 2>&1 && bag+="unindexed: $(cd "$OUT" && ls ./*.bag.active);"
  echo; echo "bags: $bag"
  python3 "$F" analyse "$OUT"; rc=$?
  echo "" >> "$OUT/faults.md"; echo "Recordings (rosbag info): $bag" >> "$OUT/faults.md"
  [[ "$bag" == *NOT* || "$bag" == *unindexed* ]] && rc=1
  return $rc
}
