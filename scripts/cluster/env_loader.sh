#!/usr/bin/env bash
# roslaunch env-loader for one machine of the deployment (the <machine env-loader="..."> script).
#
#   env_loader.sh [--ip ADDR] COMMAND [ARGS...]
#
# Sources the workspace environment (scripts/env.sh: Debian ROS, the devel space), sets ROS_IP to
# this machine's address and execs COMMAND. roslaunch calls it over ssh as
#   env ROS_MASTER_URI=<master> <env-loader> roslaunch -c <name> -u <server> ...
# The address is, first found: --ip ADDR (e.g. env-loader=".../env_loader.sh --ip 10.77.0.11"),
# $SARAS_ROS_IP, or the local address of the ssh connection this command arrived on
# ($SSH_CONNECTION's third field), which is the machine's address on the link roslaunch used.
# ROS_HOSTNAME is unset so that ROS_IP is what the nodes advertise.
set -eo pipefail
ip_addr="${SARAS_ROS_IP:-}"
if [ "${1:-}" = "--ip" ]; then
  [ $# -ge 2 ] || { echo "env_loader.sh: --ip needs an address" >&2; exit 2; }
  ip_addr="$2"
  shift 2
fi
if [ -z "$ip_addr" ] && [ -n "${SSH_CONNECTION:-}" ]; then
  ip_addr="$(echo "$SSH_CONNECTION" | awk '{print $3}')"
fi
[ $# -ge 1 ] || { echo "usage: env_loader.sh [--ip ADDR] COMMAND [ARGS...]" >&2; exit 2; }
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
# shellcheck disable=SC1091
source "$here/../env.sh"
unset ROS_HOSTNAME
if [ -n "$ip_addr" ]; then
  export ROS_IP="$ip_addr"
fi
exec "$@"
