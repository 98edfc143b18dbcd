"""`make cluster` end to end (scripts/cluster.sh): the platform on six network namespaces.

Runs scripts/cluster.sh for a short recording under a test prefix and subnet (a cluster the user
has running is left alone) and checks what a new user would: every role's nodes run on its machine
(node URIs carry the machine's address), the console stream reaches the teleop PC from the console
PC's address (the receiver's whitelist is 10.77.x.13, not loopback), the required streams are in
the bag, the report has a section per machine, and nothing is left behind. Skips without root
(exit 77). Takes several minutes on a 2-core host.
"""
import json
import os
import subprocess

import pytest
from netns_helpers import WS

PREFIX, BASE = 'sarasmk', '10.77.8'
CLUSTER_SH = WS / 'scripts' / 'cluster.sh'
EXPECTED = {'core_pc': ['/audio/microphone', '/clock_monitor', '/world_frames', '/diagnostic_aggregator'],
            'teleop_pc': ['/teleop/teleop_manager', '/touchball_receiver', '/mesa_left/saras_arms_driver',
                          '/colliding_regions'],
            'dvrk_pc': ['/dvrk/dvrk_sim', '/endoscope/endoscope_sim', '/visual_feedback'],
            'console_pc': ['/touchball_console_sim', '/clock_responder_console_pc'],
            'saras_left': ['/mesa_left/saras_arm_sim'], 'saras_right': ['/mesa_right/saras_arm_sim']}


def namespaces():
    out = subprocess.run(['ip', 'netns', 'list'], stdout=subprocess.PIPE, text=True).stdout
    return [line.split()[0] for line in out.splitlines() if line.startswith(PREFIX + '_')]


@pytest.fixture(scope='module')
def run(tmp_path_factory):
    if os.geteuid() != 0:
        pytest.skip('root is required for network namespaces')
    out = tmp_path_factory.mktemp('cluster')
    env = dict(os.environ, SARAS_NETNS_PREFIX=PREFIX, SARAS_NETNS_SUBNET=BASE + '.0/24',
               SARAS_NETNS_RUN='/tmp/%s_cluster' % PREFIX)
    proc = subprocess.run(['bash', str(CLUSTER_SH), '12', str(out)], env=env, timeout=1500,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if proc.returncode == 77:
        pytest.skip(proc.stdout[-500:])
    return proc, out


def test_cluster_runs_and_records(run):
    proc, out = run
    assert proc.returncode in (0, 1), proc.stdout[-3000:]
    assert (out / 'cluster.bag').exists()
    check = json.loads((out / 'report' / 'topics.json').read_text())
    counts = {r['topic']: r['count'] for r in check['results']}
    for topic in ('/touchball/left/state', '/mesa_left/ee_pose', '/dvrk/PSM1/position_cartesian_current',
                  '/endoscope/left/image_raw/compressed', '/teleop/tank_master/energy'):
        assert counts.get(topic, 0) > 0, topic


def test_every_role_runs_on_its_machine(run):
    _, out = run
    graph = json.loads((out / 'machines.json').read_text())['graph']
    for role, nodes in EXPECTED.items():
        assert graph['machines'][role]['address'] == '%s.%d' % (BASE, 10 + list(EXPECTED).index(role))
        for node in nodes:
            assert graph['nodes'].get(node) == role, (node, graph['nodes'].get(node))
    # the console stream crosses machines: console PC -> teleop PC, and its whitelist is the console's address
    links = json.loads((out / 'machines.json').read_text())['links']
    assert {'from': 'console_pc', 'to': 'teleop_pc', 'protocol': 'udp', 'port': 8888,
            'what': 'Touchball state packets', 'relay': ''} in links
    params = (out / 'params.yaml').read_text()
    assert 'allowed_source: %s.13' % BASE in params


def test_report_has_a_section_per_machine(run):
    _, out = run
    index = (out / 'report' / 'index.html').read_text()
    for role in EXPECTED:
        assert '<h2>Machine %s</h2>' % role in index


def test_nothing_left_behind(run):
    assert namespaces() == []
    assert not os.path.exists('/tmp/%s_cluster' % PREFIX)
