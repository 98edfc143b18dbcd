#!/usr/bin/env bash
# Run every test suite of the workspace and print one summary line per suite and a total.
#   1. catkin_lint (strict)
#   2. pytest of the workspace tests in tests/ (root pytest.ini)
#   3. catkin's run_tests: every package's gtests, rostests and pytest suite (saras_add_pytest),
#      checked with catkin_test_results
# Each test runs once; the totals count every JUnit result file (junit_counts.py): the workspace
# pytest file and everything catkin wrote under test_results/<package>/.
# Exit status is non-zero if any suite failed. Assumes `scripts/build.sh` ran (make test does).
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
cd "$SARAS_WS"
export ROS_HOME="${ROS_HOME:-$BUILD_DIR/ros_home}"
export ROS_LOG_DIR="$ROS_HOME/log"
mkdir -p "$ROS_LOG_DIR"
results_dir="$BUILD_DIR/test_results"
failed_suites=()
total_pass=0; total_fail=0; total_skip=0
# count LABEL FILE...: add the JUnit counts of FILEs to the totals and print them
count() {
  local label=$1; shift
  [ $# -eq 0 ] && return
  read -r p f s < <(python3 "$here/junit_counts.py" "$@")
  echo "$label: $p passed, $f failed, $s skipped ($# result files)"
  total_pass=$((total_pass+p)); total_fail=$((total_fail+f)); total_skip=$((total_skip+s))
}

echo "=== catkin_lint ==="
if catkin_lint -W2 --strict --ignore missing_directory src; then
  echo "catkin_lint: clean"; total_pass=$((total_pass+1))
else
  failed_suites+=(catkin_lint); total_fail=$((total_fail+1))
fi

echo "=== pytest (workspace tests) ==="
mkdir -p "$results_dir/pytest"
python3 -m pytest -q -rs --junitxml="$results_dir/pytest/pytest.xml" ${PYTEST_ARGS:-}
rc=$?
if [ $rc -ne 0 ] && [ $rc -ne 5 ]; then failed_suites+=(pytest); fi
count "workspace pytest" "$results_dir/pytest/pytest.xml"

echo "=== gtest + rostest + package pytest suites (catkin run_tests) ==="
find "$results_dir" -mindepth 1 -maxdepth 1 -not -name pytest -exec rm -rf {} +
make -C "$BUILD_DIR" -j"${JOBS:-$(nproc)}" --no-print-directory tests >/dev/null || failed_suites+=(build-tests)
make -C "$BUILD_DIR" -j1 --no-print-directory run_tests > "$BUILD_DIR/run_tests.log" 2>&1
grep -E "^\[ *(OK|FAILED|PASSED) *\]|^\[Testcase|FAILURE|ERROR:|rostest.*(PASS|FAIL)" "$BUILD_DIR/run_tests.log" | tail -n 200
if ! catkin_test_results "$results_dir" --all > "$BUILD_DIR/catkin_summary.txt" 2>&1; then
  failed_suites+=(catkin_run_tests)
fi
grep -vE "^Skipping" "$BUILD_DIR/catkin_summary.txt" | tail -n 40
mapfile -t package_pytest < <(find "$results_dir" -name 'pytest-*.xml' -not -path '*/pytest/*')
mapfile -t gtest_rostest < <(find "$results_dir" -name '*.xml' -not -path '*/pytest/*' -not -name 'pytest-*.xml')
count "package pytest suites" "${package_pytest[@]}"
count "gtest + rostest" "${gtest_rostest[@]}"

# the failed test cases last, so that a truncated CI log still names them
python3 "$here/junit_counts.py" --failures "$results_dir/pytest/pytest.xml" "${package_pytest[@]}" \
  "${gtest_rostest[@]}" | head -n 15
echo
if [ ${#failed_suites[@]} -ne 0 ]; then
  echo "FAILED suites: ${failed_suites[*]}"
  [ $total_fail -eq 0 ] && total_fail=${#failed_suites[@]}
fi
echo "total: ${total_pass} passed, ${total_fail} failed, ${total_skip} skipped"
[ ${#failed_suites[@]} -eq 0 ]
