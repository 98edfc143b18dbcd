#!/usr/bin/env bash
# roslaunch env-loader for one machine of the deployment (the <machine env-loader="..."> script).
#
#   env_loader.sh [--ip ADDR] [--faketime OFFSET] COMMAND [ARGS...]
#
# Sources the workspace environment (scripts/env.sh: Debian ROS, the devel space), sets ROS_IP to
# this machine's address and execs COMMAND. roslaunch calls it over ssh as
#   env ROS_MASTER_URI=<master> <env-loader> roslaunch -c <name> -u <server> ...
# The address is, first found: --ip ADDR (e.g. env-loader=".../env_loader.sh --ip 10.77.0.11"),
# $SARAS_ROS_IP, or the local address of the ssh connection this command arrived on
# ($SSH_CONNECTION's third field), which is the machine's address on the link roslaunch used.
# ROS_HOSTNAME is unset so that ROS_IP is what the nodes advertise.
# --faketime OFFSET (testing only) runs the machine's processes with a shifted wall clock:
# libfaketime preloaded with FAKETIME=OFFSET (seconds with sign and fraction, e.g. +0.05).
set -eo pipefail
ip_addr="${SARAS_ROS_IP:-}"
faketime=""
while [ "${1:-}" = "--ip" ] || [ "${1:-}" = "--faketime" ]; do
  [ $# -ge 2 ] || { echo "env_loader.sh: $1 needs a value" >&2; exit 2; }
  if [ "$1" = "--ip" ]; then ip_addr="$2"; else faketime="$2"; fi
  shift 2
done
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
if [ -n "$faketime" ]; then
  [[ "$faketime" =~ ^[+-]?[0-9]+(\.[0-9]+)?$ ]] || { echo "env_loader.sh: --faketime '$faketime': [+-]S.FFF" >&2; exit 2; }
  [[ "$faketime" =~ ^[+-] ]] || faketime="+$faketime"  # roslaunch's eval drops a '+'; unsigned = ahead
  lib="$(ls /usr/lib/*/faketime/libfaketime.so.1 2>/dev/null | head -n 1)"
  [ -n "$lib" ] || { echo "env_loader.sh: --faketime needs libfaketime (Debian faketime)" >&2; exit 2; }
  export LD_PRELOAD="$lib${LD_PRELOAD:+:$LD_PRELOAD}" FAKETIME="$faketime" FAKETIME_NO_CACHE=1
fi
exec "$@"
