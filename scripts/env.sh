# Source me: the environment every project script uses.
# Debian's ROS Noetic lives in /usr; a pyenv/conda python3 earlier on PATH cannot see its
# modules, so /usr/bin goes first. Then the workspace's devel space is overlaid if built.
export PATH=/usr/bin:/bin:/usr/sbin:/sbin:$PATH
SARAS_WS="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
export SARAS_WS
export PYTHONNOUSERSITE=1
unset PYTHONHOME PYENV_VERSION VIRTUAL_ENV
if [ -f "$SARAS_WS/devel/setup.bash" ]; then
  # shellcheck disable=SC1091
  source "$SARAS_WS/devel/setup.bash"
fi
export ROS_PYTHON_VERSION=3
