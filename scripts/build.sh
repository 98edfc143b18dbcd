#!/usr/bin/env bash
# Configure and build the catkin workspace.
#   BUILD_DIR / DEVEL_DIR  where to build (default build/ and devel/ at the repository root)
#   PACKAGES               optional ';'-separated whitelist (e.g. "saras_msgs;saras_collision")
#   BUILD_TYPE, JOBS       CMake build type (RelWithDebInfo) and make -j (nproc)
# Extra arguments are passed to make (e.g. a target name).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
cd "$SARAS_WS"
BUILD_TYPE="${BUILD_TYPE:-RelWithDebInfo}"
JOBS="${JOBS:-$(nproc)}"
mkdir -p "$BUILD_DIR" "$DEVEL_DIR"
touch "$BUILD_DIR/CATKIN_IGNORE" "$DEVEL_DIR/CATKIN_IGNORE"
configure() {
  cmake -S . -B "$BUILD_DIR" -DCATKIN_DEVEL_PREFIX="$DEVEL_DIR" \
    -DCMAKE_INSTALL_PREFIX="$SARAS_WS/install" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON \
    -DCATKIN_WHITELIST_PACKAGES="${PACKAGES:-}" > "$BUILD_DIR/cmake.log" 2>&1 \
    || { cat "$BUILD_DIR/cmake.log"; exit 1; }
}
fresh_devel=0
[ -f "$DEVEL_DIR/setup.bash" ] || fresh_devel=1
configure
if [ "$fresh_devel" = 1 ]; then
  # catkin caches the environment of the configure run (catkin_generated/setup_cached.sh) as a diff
  # against the calling environment; on a fresh devel space that snapshot misses the devel space's
  # own Python path, and every test run through catkin's env would fail to import the workspace
  # modules. Configure once more with the new devel space sourced.
  # shellcheck disable=SC1091
  source "$here/env.sh"
  configure
fi
make -C "$BUILD_DIR" -j"$JOBS" --no-print-directory "$@"
