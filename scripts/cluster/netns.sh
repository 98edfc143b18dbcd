#!/usr/bin/env bash
# The SARAS deployment of D7.2 Section 2 as Linux network namespaces on this host.
#
#   netns.sh up | down | status | exec ROLE CMD... | ssh ROLE CMD...
#
# `up` creates one namespace "<prefix>_lan" holding a bridge (br0) and one namespace per machine
# role, "<prefix>_<role>", joined to the bridge by a veth pair (eth0 inside the role namespace),
# each with its own address in a private /24 and loopback up. Every role namespace runs an sshd
# listening only on its own address, so roslaunch <machine> tags (paramiko) can start nodes in any
# namespace from the core_pc namespace. Keys are created for the run in the run directory:
#   <run>/home/.ssh/{id_ed25519,known_hosts,config}  client HOME (HOME=<run>/home for roslaunch;
#                                                     `ssh -F <run>/home/.ssh/config ADDR` by hand)
#   <run>/<role>/{ssh_host_ed25519_key,sshd_config,sshd.log}
#   <run>/cluster.env                                 addresses, namespaces, master URI (sourceable)
# `down` kills every process inside these namespaces, deletes the namespaces (which removes the
# bridge and the veth pairs) and the run directory; it is idempotent and is also run when `up`
# fails or is interrupted. `exec ROLE CMD` runs CMD in ROLE's namespace with ROS_IP, ROS_MASTER_URI
# and HOME set; `ssh ROLE CMD` runs CMD on ROLE through its sshd. No link or address is ever
# created in the host's own namespace.
#
# Environment (defaults in brackets):
#   SARAS_NETNS_PREFIX  namespace name prefix            [saras]
#   SARAS_NETNS_SUBNET  private /24 of the deployment    [10.77.0.0/24]
#   SARAS_NETNS_ROLES   machine roles, the first one is the ROS core
#                       [core_pc teleop_pc dvrk_pc console_pc saras_left saras_right]
#   SARAS_NETNS_RUN     run directory                    [/tmp/<prefix>_cluster]
# Role i (0-based) gets host address 10+i: core_pc 10.77.0.10, teleop_pc .11, dvrk_pc .12, ...
# Root is required; without it (or without network-namespace support) the script exits 77.
set -Eeuo pipefail
export PATH=/usr/sbin:/usr/bin:/sbin:/bin:$PATH

PREFIX="${SARAS_NETNS_PREFIX:-saras}"
SUBNET="${SARAS_NETNS_SUBNET:-10.77.0.0/24}"
DEFAULT_ROLES="core_pc teleop_pc dvrk_pc console_pc saras_left saras_right"
read -r -a ROLES <<< "${SARAS_NETNS_ROLES:-$DEFAULT_ROLES}"
RUN="${SARAS_NETNS_RUN:-/tmp/${PREFIX}_cluster}"
LAN="${PREFIX}_lan"
MARKER=".saras_netns_run"
HOST_BASE=10

die() { echo "netns.sh: $*" >&2; exit 1; }
skip() { echo "netns.sh: SKIP: $*" >&2; exit 77; }

check_config() {
  [[ "$PREFIX" =~ ^[a-z][a-z0-9]{0,11}$ ]] || die "SARAS_NETNS_PREFIX '$PREFIX': 1-12 of [a-z0-9]"
  [[ "$SUBNET" =~ ^([0-9]+)\.([0-9]+)\.([0-9]+)\.0/24$ ]] \
    || die "SARAS_NETNS_SUBNET '$SUBNET' must be a /24 written a.b.c.0/24"
  BASE="${BASH_REMATCH[1]}.${BASH_REMATCH[2]}.${BASH_REMATCH[3]}"
  [ "${#ROLES[@]}" -ge 1 ] && [ "${#ROLES[@]}" -le 200 ] || die "1..200 roles expected"
  local r
  for r in "${ROLES[@]}"; do
    [[ "$r" =~ ^[a-z][a-z0-9_]*$ ]] || die "role name '$r': [a-z][a-z0-9_]*"
  done
}

require_root() {
  [ "$(id -u)" = 0 ] || skip "root is required (network namespaces, sshd)"
  local t="${PREFIX}_probe$$"
  ip netns add "$t" 2>/dev/null || skip "cannot create network namespaces here"
  ip netns del "$t"
  command -v /usr/sbin/sshd >/dev/null && command -v ssh-keygen >/dev/null \
    || skip "openssh-server / ssh-keygen not installed"
}

ns_of() { echo "${PREFIX}_$1"; }
addr_of() {  # addr_of ROLE
  local i
  for i in "${!ROLES[@]}"; do
    [ "${ROLES[$i]}" = "$1" ] && { echo "$BASE.$((HOST_BASE + i))"; return 0; }
  done
  die "unknown role '$1' (roles: ${ROLES[*]})"
}
ns_exists() { ip netns list | awk '{print $1}' | grep -qx "$1"; }

make_keys() {
  mkdir -p "$RUN/home/.ssh"
  chmod 700 "$RUN" "$RUN/home" "$RUN/home/.ssh"
  touch "$RUN/$MARKER"
  ssh-keygen -q -t ed25519 -N "" -C "saras-cluster-client" -f "$RUN/home/.ssh/id_ed25519"
  cp "$RUN/home/.ssh/id_ed25519.pub" "$RUN/authorized_keys"
  : > "$RUN/home/.ssh/known_hosts"
  cat > "$RUN/home/.ssh/config" <<EOF
Host *
  User root
  IdentityFile $RUN/home/.ssh/id_ed25519
  IdentitiesOnly yes
  UserKnownHostsFile $RUN/home/.ssh/known_hosts
  GlobalKnownHostsFile /dev/null
  StrictHostKeyChecking yes
  BatchMode yes
  ConnectTimeout 5
EOF
  if [ ! -d /run/sshd ]; then  # privilege-separation directory sshd insists on
    mkdir -p /run/sshd && chmod 755 /run/sshd && touch "$RUN/created_run_sshd"
  fi
}

make_lan() {
  ip netns add "$LAN"
  ip -n "$LAN" link set lo up
  ip -n "$LAN" link add br0 type bridge
  ip -n "$LAN" link set br0 up
}

make_machine() {  # make_machine INDEX ROLE
  local i="$1" role="$2" ns addr
  ns="$(ns_of "$role")"; addr="$(addr_of "$role")"
  ip netns add "$ns"
  ip -n "$ns" link set lo up
  ip -n "$LAN" link add "veth$i" type veth peer name eth0 netns "$ns"
  ip -n "$LAN" link set "veth$i" master br0 up
  ip -n "$ns" addr add "$addr/24" dev eth0
  ip -n "$ns" link set eth0 up
  start_sshd "$role" "$ns" "$addr"
}

start_sshd() {  # start_sshd ROLE NS ADDR
  local role="$1" ns="$2" addr="$3" d="$RUN/$1"
  mkdir -p "$d"
  ssh-keygen -q -t ed25519 -N "" -C "saras-cluster-$role" -f "$d/ssh_host_ed25519_key"
  cat > "$d/sshd_config" <<EOF
ListenAddress $addr
Port 22
HostKey $d/ssh_host_ed25519_key
PidFile $d/sshd.pid
AuthorizedKeysFile $RUN/authorized_keys
PermitRootLogin prohibit-password
PubkeyAuthentication yes
PasswordAuthentication no
KbdInteractiveAuthentication no
UsePAM no
StrictModes no
X11Forwarding no
PrintMotd no
MaxStartups 50
EOF
  ip netns exec "$ns" /usr/sbin/sshd -f "$d/sshd_config" -E "$d/sshd.log"
  echo "$addr ssh-ed25519 $(awk '{print $2}' "$d/ssh_host_ed25519_key.pub")" \
    >> "$RUN/home/.ssh/known_hosts"
}

wait_listening() {  # every sshd accepts TCP on ADDR:22 within 5 s
  local role ns addr n
  for role in "${ROLES[@]}"; do
    ns="$(ns_of "$role")"; addr="$(addr_of "$role")"
    for n in $(seq 50); do
      ip netns exec "$ns" ss -Hltn "src $addr:22" | grep -q LISTEN && break
      [ "$n" = 50 ] && die "sshd of $role not listening on $addr:22 (see $RUN/$role/sshd.log)"
      sleep 0.1
    done
  done
}

write_env() {
  local role core="${ROLES[0]}"
  {
    echo "# written by scripts/cluster/netns.sh up; source it"
    echo "SARAS_NETNS_PREFIX=$PREFIX"
    echo "SARAS_NETNS_RUN=$RUN"
    echo "SARAS_CLUSTER_HOME=$RUN/home"
    echo "SARAS_MASTER_URI=http://$(addr_of "$core"):11311"
    for role in "${ROLES[@]}"; do
      echo "SARAS_ADDR_$role=$(addr_of "$role")"
      echo "SARAS_NS_$role=$(ns_of "$role")"
    done
  } > "$RUN/cluster.env"
}

cmd_up() {
  require_root
  ns_exists "$LAN" && die "already up ($LAN exists); run '$0 down' first"
  [ -e "$RUN" ] && [ ! -f "$RUN/$MARKER" ] && die "run directory $RUN exists and is not ours"
  rm -rf "$RUN"
  trap 'echo "netns.sh: up failed, tearing down" >&2; cmd_down; exit 1' ERR
  trap 'echo "netns.sh: interrupted, tearing down" >&2; cmd_down; exit 130' INT TERM
  mkdir -p "$RUN"
  make_keys
  make_lan
  local i
  for i in "${!ROLES[@]}"; do make_machine "$i" "${ROLES[$i]}"; done
  wait_listening
  write_env
  trap - ERR INT TERM
  echo "netns.sh: up: ${#ROLES[@]} machines on $SUBNET (bridge in $LAN), run directory $RUN"
  cmd_status
}

kill_ns_processes() {  # TERM, then KILL, every process whose network namespace is NS
  local ns="$1" pids n
  pids="$(ip netns pids "$ns" 2>/dev/null || true)"
  [ -z "$pids" ] && return 0
  # shellcheck disable=SC2086
  kill -TERM $pids 2>/dev/null || true
  for n in $(seq 30); do
    pids="$(ip netns pids "$ns" 2>/dev/null || true)"
    [ -z "$pids" ] && return 0
    sleep 0.1
  done
  # shellcheck disable=SC2086
  kill -KILL $pids 2>/dev/null || true
  sleep 0.1
}

our_namespaces() {  # every namespace this prefix may have made (roles of any configuration)
  ip netns list | awk '{print $1}' | grep -E "^${PREFIX}_(lan|[a-z][a-z0-9_]*)$" || true
}

cmd_down() {
  require_root
  local ns
  for ns in $(our_namespaces); do kill_ns_processes "$ns"; done
  for ns in $(our_namespaces); do ip netns del "$ns" 2>/dev/null || true; done
  if [ -f "$RUN/$MARKER" ]; then
    if [ -f "$RUN/created_run_sshd" ] && ! pgrep -x sshd >/dev/null; then
      rmdir /run/sshd 2>/dev/null || true
    fi
    rm -rf "$RUN"
  fi
  [ -z "$(our_namespaces)" ] || die "namespaces left: $(our_namespaces | tr '\n' ' ')"
  echo "netns.sh: down: no ${PREFIX}_* namespace left"
}

cmd_status() {
  require_root
  local role ns addr ok=0 state
  ns_exists "$LAN" && echo "lan        $LAN (br0)" || { echo "lan        $LAN missing"; ok=3; }
  for role in "${ROLES[@]}"; do
    ns="$(ns_of "$role")"; addr="$(addr_of "$role")"
    if ! ns_exists "$ns"; then
      state="missing"; ok=3
    elif ip netns exec "$ns" ss -Hltn "src $addr:22" | grep -q LISTEN; then
      state="up, sshd on $addr:22"
    else
      state="up, sshd NOT listening"; ok=3
    fi
    printf '%-12s %-22s %-14s %s\n' "$role" "$ns" "$addr" "$state"
  done
  return "$ok"
}

cmd_exec() {  # cmd_exec ROLE CMD...: replaces this shell by CMD in ROLE's namespace
  require_root
  local role="$1" ns ip master; shift
  ns="$(ns_of "$role")"; ip="$(addr_of "$role")"; master="http://$(addr_of "${ROLES[0]}"):11311"
  # exec: CMD gets this process id, so that the caller's signals (SIGINT to stop roslaunch) reach it
  exec ip netns exec "$ns" env HOME="$RUN/home" ROS_IP="$ip" ROS_MASTER_URI="$master" SARAS_ROS_IP="$ip" "$@"
}

cmd_ssh() {  # cmd_ssh ROLE CMD...: from the core namespace, through ROLE's sshd
  require_root
  local role="$1"; shift
  ip netns exec "$(ns_of "${ROLES[0]}")" ssh -F "$RUN/home/.ssh/config" "$(addr_of "$role")" "$@"
}

main() {
  check_config
  case "${1:-}" in
    up) cmd_up ;;
    down) cmd_down ;;
    status) cmd_status ;;
    exec) [ $# -ge 3 ] || die "usage: $0 exec ROLE CMD..."; shift; cmd_exec "$@" ;;
    ssh) [ $# -ge 3 ] || die "usage: $0 ssh ROLE CMD..."; shift; cmd_ssh "$@" ;;
    *) echo "usage: $0 up|down|status|exec ROLE CMD...|ssh ROLE CMD..." >&2; exit 2 ;;
  esac
}

main "$@"
