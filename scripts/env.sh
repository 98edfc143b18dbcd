# Source me: the environment every project script uses.
# Debian's ROS Noetic lives in /usr; a pyenv/conda python3 earlier on PATH cannot see its
# modules, so /usr/bin goes first. Then the workspace's devel space is overlaid if built.
#   DEVEL_DIR  devel space to overlay (default <ws>/devel; scripts/build.sh honours the same variable)
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
SARAS_WS="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export SARAS_WS
export DEVEL_DIR="${DEVEL_DIR:-$SARAS_WS/devel}"
export BUILD_DIR="${BUILD_DIR:-$SARAS_WS/build}"
export PYTHONNOUSERSITE=1
unset PYTHONHOME PYENV_VERSION VIRTUAL_ENV
if [ -f "$DEVEL_DIR/setup.bash" ]; then
  # catkin's setup scripts read unset variables: relax `set -u` while sourcing
  case $- in *u*) _saras_nounset=1; set +u ;; *) _saras_nounset=0 ;; esac
  # shellcheck disable=SC1091
  source "$DEVEL_DIR/setup.bash"
  [ "$_saras_nounset" = 1 ] && set -u
  unset _saras_nounset
fi
export ROS_PYTHON_VERSION=3
