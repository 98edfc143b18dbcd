#!/usr/bin/env bash
# Configure and build the catkin workspace (build/ and devel/ at the repository root).
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
cd "$SARAS_WS"
BUILD_TYPE="${BUILD_TYPE:-RelWithDebInfo}"
JOBS="${JOBS:-$(nproc)}"
mkdir -p build devel
touch build/CATKIN_IGNORE devel/CATKIN_IGNORE
cmake -S . -B build -DCATKIN_DEVEL_PREFIX="$SARAS_WS/devel" \
  -DCMAKE_INSTALL_PREFIX="$SARAS_WS/install" -DCMAKE_BUILD_TYPE="$BUILD_TYPE" \
  -DPYTHON_EXECUTABLE=/usr/bin/python3 -DCATKIN_ENABLE_TESTING=ON > build/cmake.log \
  || { cat build/cmake.log; exit 1; }
make -C build -j"$JOBS" --no-print-directory "$@"
