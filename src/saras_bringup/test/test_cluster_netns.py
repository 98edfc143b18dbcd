"""The namespace deployment (scripts/cluster/netns.sh): addresses, ssh, roslaunch machine tags.

Brings the six D7.2 machines up as network namespaces under a test prefix and subnet (so a cluster
the user has running is left alone), checks reachability over the bridge, OpenSSH and paramiko
(roslaunch's own known_hosts check), a roscore in core_pc used from teleop_pc over TCP, a node
started on teleop_pc by a roslaunch <machine> tag, and that `down` leaves nothing behind.
Skips without root (netns.sh exits 77).
"""
import os
import signal
import subprocess
import time
from pathlib import Path

import pytest
from netns_helpers import NETNS, WS, Deployment

SMOKE_LAUNCH = Path(__file__).resolve().parent / 'launch' / 'cluster_smoke.launch'
ENV_LOADER = WS / 'scripts' / 'cluster' / 'env_loader.sh'
CLUSTER = Deployment('sarastest', '10.77.9')
PREFIX, BASE, RUN, ADDR, ENV = (CLUSTER.prefix, CLUSTER.base, CLUSTER.run_dir, CLUSTER.addr,
                                CLUSTER.env)
netns, in_ns = CLUSTER.netns, CLUSTER.in_ns

PARAMIKO_CHECK = '''
import sys, paramiko
from roslaunch.remoteprocess import ssh_check_known_hosts
ssh = paramiko.SSHClient()
err = ssh_check_known_hosts(ssh, sys.argv[1], 22)
assert err is None, err
ssh.connect(sys.argv[1], 22, None, timeout=10)
_, out, _ = ssh.exec_command('echo $SSH_CONNECTION')
print(out.read().decode().strip())
'''


def our_processes():
    """Live (non-zombie) processes whose command line names the test run directory."""
    found = []
    for pid in os.listdir('/proc'):
        if not pid.isdigit():
            continue
        try:
            cmdline = Path('/proc', pid, 'cmdline').read_bytes().replace(b'\0', b' ').decode()
            state = Path('/proc', pid, 'stat').read_text().rsplit(')', 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        if RUN in cmdline and state != 'Z':
            found.append(cmdline)
    return found


@pytest.fixture(scope='module')
def cluster():
    CLUSTER.up_or_skip()
    yield
    CLUSTER.down()


@pytest.fixture(scope='module')
def roscore(cluster):
    core = CLUSTER.popen('core_pc', 'roscore', '-p', '11311', stdout=subprocess.DEVNULL,
                         stderr=subprocess.DEVNULL)
    CLUSTER.wait_master('teleop_pc')
    yield core
    if core.poll() is None:  # test_down_leaves_nothing normally stopped it already
        os.killpg(core.pid, signal.SIGINT)
        core.wait(timeout=30)


def test_every_machine_reachable_over_the_bridge(cluster):
    probe = ('import socket,sys\nfor a in sys.argv[1:]:\n'
             '    socket.create_connection((a, 22), timeout=5).close()\nprint("ok")')
    for src in ('core_pc', 'saras_right'):
        r = in_ns(src, '/usr/bin/python3', '-c', probe, *ADDR.values())
        assert r.stdout.strip().endswith('ok'), r.stdout
    host = subprocess.run(['ip', '-br', 'addr'], stdout=subprocess.PIPE, text=True, check=True)
    assert BASE + '.' not in host.stdout, 'an address of the deployment leaked into the host'


def test_openssh_from_core_to_teleop(cluster):
    r = netns('ssh', 'teleop_pc', 'echo $SSH_CONNECTION; ip -br addr show eth0', check=False)
    assert r.returncode == 0, r.stdout
    assert r.stdout.split()[0] == ADDR['core_pc'] and r.stdout.split()[2] == ADDR['teleop_pc']
    assert ADDR['teleop_pc'] + '/24' in r.stdout


@pytest.mark.parametrize('role', ['teleop_pc', 'saras_left'])
def test_paramiko_accepts_the_run_home(cluster, role):
    r = in_ns('core_pc', '/usr/bin/python3', '-c', PARAMIKO_CHECK, ADDR[role])
    assert r.returncode == 0, r.stdout
    assert r.stdout.split()[-2:] == [ADDR[role], '22']


def test_roscore_in_core_used_from_teleop(roscore):
    r = in_ns('teleop_pc', 'rosparam', 'set', '/cluster_probe', '42')
    assert r.returncode == 0, r.stdout
    r = in_ns('dvrk_pc', 'rosparam', 'get', '/cluster_probe')
    assert r.stdout.strip() == '42', r.stdout
    r = in_ns('teleop_pc', 'rostopic', 'list')
    assert '/rosout' in r.stdout.split(), r.stdout
    r = in_ns('teleop_pc', 'rosnode', 'info', '/rosout')
    assert 'http://%s:' % ADDR['core_pc'] in r.stdout, r.stdout


def test_roslaunch_machine_tag_starts_node_on_teleop(roscore):
    launch = CLUSTER.popen('core_pc', 'roslaunch', str(SMOKE_LAUNCH),
                           'core_addr:=' + ADDR['core_pc'], 'remote_addr:=' + ADDR['teleop_pc'],
                           'env_loader:=' + str(ENV_LOADER),
                           stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    try:
        r = in_ns('core_pc', 'rostopic', 'echo', '-n', '1', '/cluster_smoke', timeout=60)
        assert 'data: "hi"' in r.stdout, r.stdout
        r = in_ns('core_pc', 'rosnode', 'info', '/cluster_smoke_talker')
        assert 'contacting node http://%s:' % ADDR['teleop_pc'] in r.stdout, r.stdout
    finally:
        os.killpg(launch.pid, signal.SIGINT)
        out, _ = launch.communicate(timeout=60)
    assert 'creating ssh connection to %s:22' % ADDR['teleop_pc'] in out, out


def test_down_leaves_nothing(cluster):
    r = netns('down', check=False)
    assert r.returncode == 0, r.stdout
    listed = subprocess.run(['ip', 'netns', 'list'], stdout=subprocess.PIPE, text=True).stdout
    assert PREFIX + '_' not in listed
    assert not Path(RUN).exists()
    deadline = time.monotonic() + 5
    while our_processes() and time.monotonic() < deadline:
        time.sleep(0.2)
    assert our_processes() == []
    assert netns('down', check=False).returncode == 0, 'down is not idempotent'
    assert netns('status', check=False).returncode == 3


def test_without_root_exits_77():
    if os.geteuid() != 0:
        r = netns('status', check=False)
    else:
        r = subprocess.run(['setpriv', '--reuid=65534', '--regid=65534', '--clear-groups',
                            'bash', str(NETNS), 'status'], env=ENV, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, text=True, timeout=30)
    assert r.returncode == 77, r.stdout
    assert 'root is required' in r.stdout
