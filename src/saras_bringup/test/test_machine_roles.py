"""launch/platform.launch (one host) and launch/cluster.launch (six machines) start the same nodes
with the same parameters, and each node on the machine whose role file starts it.

No master needed: roslaunch's own config loader (roslaunch.config.load_config_default) resolves
the launch files as `roslaunch` would.
"""
import os
import re

import pytest

roslaunch_config = pytest.importorskip('roslaunch.config')

WS = os.path.realpath(os.path.join(os.path.dirname(__file__), '..', '..', '..'))
LAUNCH = os.path.join(WS, 'launch')
ROLES = ['core_pc', 'teleop_pc', 'dvrk_pc', 'console_pc', 'saras_left', 'saras_right']
CLUSTER_ADDR = {'core_addr': '10.77.0.10', 'teleop_addr': '10.77.0.11', 'dvrk_addr': '10.77.0.12',
                'console_addr': '10.77.0.13', 'saras_left_addr': '10.77.0.14',
                'saras_right_addr': '10.77.0.15'}
LOOPBACK = {k: '127.0.0.1' for k in CLUSTER_ADDR}
# the loader's own parameters (present in every config)
LOADER_PARAMS = {'/rosdistro', '/rosversion', '/run_id'}


def load(path, **args):
    argv = ['%s:=%s' % kv for kv in sorted(args.items())]
    return roslaunch_config.load_config_default([(path, argv)], None, verbose=False)


def node_key(n):
    return (n.namespace.rstrip('/') + '/' + n.name)


def node_sig(n):
    args = ' '.join(os.path.normpath(a) if a.startswith('/') else a for a in n.args.split())
    return (n.package, n.type, args, tuple(sorted(n.remap_args)), n.launch_prefix or '', n.required)


def nodes(cfg):
    return {node_key(n): node_sig(n) for n in cfg.nodes}


def params(cfg):
    return {k: p.value for k, p in cfg.params.items() if k not in LOADER_PARAMS}


@pytest.fixture(scope='module')
def platform():
    return load(os.path.join(LAUNCH, 'platform.launch'), console_bind='127.0.0.1')


@pytest.fixture(scope='module')
def cluster():
    return load(os.path.join(LAUNCH, 'cluster.launch'), **CLUSTER_ADDR)


@pytest.fixture(scope='module')
def roles():
    return {r: load(os.path.join(LAUNCH, 'machines', r + '.launch')) for r in ROLES}


def test_platform_starts_the_simulated_platform(platform):
    names = set(nodes(platform))
    for n in ['/teleop/teleop_manager', '/touchball_receiver', '/touchball_console_sim',
              '/mesa_left/saras_arm_sim', '/mesa_right/saras_arms_driver', '/dvrk/dvrk_sim',
              '/endoscope/endoscope_sim', '/visual_feedback', '/colliding_regions', '/recorder',
              '/clock_monitor', '/clock_responder_teleop_pc', '/diagnostic_aggregator']:
        assert n in names, n
    assert len(names) >= 35


def test_cluster_on_loopback_equals_platform(platform):
    """Same nodes, same parameters when every machine address is the loopback address (and the
    teleoperation's streams recorded in-process, as on one host)."""
    on_one_host = load(os.path.join(LAUNCH, 'cluster.launch'), rviz='true', record_in_process='true',
                       bag=os.path.join(WS, 'out', 'platform.bag'), **LOOPBACK)
    assert nodes(on_one_host) == nodes(platform)
    assert params(on_one_host) == params(platform)


def test_roles_partition_platform(platform, roles):
    """Every node of the platform is started by exactly one role; the roles' parameters are the platform's."""
    seen = {}
    for role, cfg in roles.items():
        for name in nodes(cfg):
            assert name not in seen, '%s started by %s and %s' % (name, seen.get(name), role)
            seen[name] = role
    union = {}
    for cfg in roles.values():
        union.update(nodes(cfg))
    plat = nodes(platform)
    plat_default = nodes(load(os.path.join(LAUNCH, 'platform.launch')))
    assert union == plat_default
    assert set(union) == set(plat)
    union_params = {}
    for cfg in roles.values():
        union_params.update(params(cfg))
    assert union_params == params(load(os.path.join(LAUNCH, 'platform.launch')))


def test_cluster_puts_each_node_on_its_role_machine(cluster, roles):
    owner = {name: role for role, cfg in roles.items() for name in nodes(cfg)}
    assert sorted(m for m in cluster.machines if m) == sorted(ROLES)  # '' is roslaunch's local default
    for n in cluster.nodes:
        assert n.machine_name == owner[node_key(n)], node_key(n)
    for role in ROLES:
        m = cluster.machines[role]
        assert m.address == CLUSTER_ADDR[{'core_pc': 'core_addr', 'teleop_pc': 'teleop_addr',
                                          'dvrk_pc': 'dvrk_addr', 'console_pc': 'console_addr'}
                                         .get(role, role + '_addr')]
        assert m.env_loader.endswith('scripts/cluster/env_loader.sh')
        assert os.path.exists(m.env_loader)


def test_cluster_addresses_are_the_machines(cluster):
    """No loopback address is left once the machines have their own; each link uses the right one."""
    p = params(cluster)
    loop = {k: v for k, v in p.items() if isinstance(v, str) and '127.0.0.1' in v}
    # the operator view page is served on the core PC's loopback by design (saras_operator_view README)
    assert loop == {'/operator_view/bind_address': '127.0.0.1'}
    assert p['/touchball_receiver/allowed_source'] == '10.77.0.13'
    assert p['/touchball_receiver/bind_address'] == '10.77.0.11'
    assert p['/touchball_console_sim/target_address'] == '10.77.0.11'
    assert p['/touchball_console_sim/command_address'] == '10.77.0.13'
    assert p['/mesa_left/saras_arms_driver/host'] == '10.77.0.14'
    assert p['/mesa_right/saras_arms_state/host'] == '10.77.0.15'
    assert p['/mesa_right/saras_arm_sim/host'] == '10.77.0.15'


def test_relay_ports_reach_the_right_nodes():
    """A relay in a link: the client's target and the server's listening port are separate arguments."""
    cfg = load(os.path.join(LAUNCH, 'cluster.launch'), left_arm_host='10.77.0.11', left_arm_port='15001',
               left_arm_serve_port='5001',
               console_target='10.77.0.13', console_target_port='16000', console_listen_port='5016',
               **CLUSTER_ADDR)
    p = params(cfg)
    assert (p['/mesa_left/saras_arms_driver/host'], p['/mesa_left/saras_arms_driver/port']) == ('10.77.0.11', 15001)
    assert (p['/mesa_left/saras_arm_sim/host'], p['/mesa_left/saras_arm_sim/port']) == ('10.77.0.14', 5001)
    assert (p['/touchball_console_sim/target_address'], p['/touchball_console_sim/target_port']) == ('10.77.0.13', 16000)
    assert p['/touchball_console_sim/command_port'] == 5016
    assert p['/touchball_receiver/command_port'] == 5006
    assert p['/touchball_receiver/port'] == 8888


IPV4 = re.compile(r'\b\d{1,3}\.\d{1,3}\.\d{1,3}\.\d{1,3}\b')
ARG_DEFAULT = re.compile(r'<arg\s[^>]*default="[^"]*"')


@pytest.mark.parametrize('role', ROLES + ['saras_controller', 'deployment'])
def test_role_files_take_addresses_as_arguments(role):
    """An address or port number appears in a role file only as an argument's default."""
    with open(os.path.join(LAUNCH, 'machines', role + '.launch')) as f:
        text = re.sub(r'<!--.*?-->', '', f.read(), flags=re.S)
    text = ARG_DEFAULT.sub('', text)
    assert IPV4.findall(text) == []
    assert re.findall(r'value="\d{4,5}"', text) == []


def test_faketime_applies_to_one_machine_only():
    cfg = load(os.path.join(LAUNCH, 'cluster.launch'), faketime_machine='dvrk_pc', faketime='+0.05', **CLUSTER_ADDR)
    loaders = {r: cfg.machines[r].env_loader for r in ROLES}
    assert loaders['dvrk_pc'].endswith('env_loader.sh --faketime 0.05')
    assert all(v.endswith('env_loader.sh') for r, v in loaders.items() if r != 'dvrk_pc')
