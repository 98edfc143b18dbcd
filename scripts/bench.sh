#!/usr/bin/env bash
# Run every package benchmark (src/*/bench/run) and print their tables.
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
# shellcheck disable=SC1091
source "$here/env.sh"
rc=0
for b in "$SARAS_WS"/src/*/bench/run; do
  [ -x "$b" ] || continue
  echo "=== $(basename "$(dirname "$(dirname "$b")")") ==="
  "$b" || { echo "benchmark $b failed"; rc=1; }
done
exit $rc
