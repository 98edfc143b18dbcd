"""Workspace-level checks: README entry points, CI, setup idempotence, package manifests and
platform.launch resolving to real executables in simulation and hardware configurations."""
import os
import re
import subprocess
import xml.etree.ElementTree as ET

import pytest

WS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PACKAGES = sorted(d for d in os.listdir(os.path.join(WS, 'src'))
                  if os.path.exists(os.path.join(WS, 'src', d, 'package.xml')))
LAYOUT = ['saras_teleop', 'saras_collision', 'saras_visual_feedback', 'saras_drivers', 'saras_simulation',
          'saras_description', 'saras_calibration', 'saras_msgs', 'saras_bringup']


def test_layout_matches_the_design_card():
    for d in ('CMakeLists.txt', 'launch/platform.launch', 'tests', 'Makefile', 'README.md', '.ci/run'):
        assert os.path.exists(os.path.join(WS, d)), d
    assert set(LAYOUT) <= set(PACKAGES)


def test_readme_starts_with_the_two_commands_and_ci_runs_the_test_one():
    with open(os.path.join(WS, 'README.md')) as f:
        readme = f.read()
    first_block = re.search(r'```(?:bash|sh)?\n(.*?)```', readme, re.S).group(1)
    commands = [l.split('#')[0].strip() for l in first_block.splitlines() if l.split('#')[0].strip()]
    assert commands[:2] == ['make demo', 'make test']
    with open(os.path.join(WS, '.ci', 'run')) as f:
        ci = [l.strip() for l in f if l.strip() and not l.startswith('#')]
    assert ci[-1] == 'make test'


def test_setup_is_idempotent_when_everything_is_installed():
    out = subprocess.run(['bash', os.path.join(WS, 'scripts', 'setup.sh')], capture_output=True,
                         text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert re.search(r'all \d+ Debian packages present', out.stdout), out.stdout


@pytest.mark.parametrize('pkg', PACKAGES)
def test_package_manifest_format_3(pkg):
    root = ET.parse(os.path.join(WS, 'src', pkg, 'package.xml')).getroot()
    assert root.get('format') == '3'
    assert root.findtext('name') == pkg
    assert root.findtext('license')


@pytest.mark.parametrize('pkg', PACKAGES)
def test_scripts_are_installed(pkg):
    """Every executable in scripts/ is installed (catkin_install_python by name or by glob)."""
    sdir = os.path.join(WS, 'src', pkg, 'scripts')
    if not os.path.isdir(sdir):
        pytest.skip('no scripts/')
    with open(os.path.join(WS, 'src', pkg, 'CMakeLists.txt')) as f:
        cmake = f.read()
    globbed = re.search(r'GLOB\s+\w+[^)]*scripts/\*', cmake) is not None
    for name in os.listdir(sdir):
        path = os.path.join(sdir, name)
        if os.path.isfile(path) and os.access(path, os.X_OK):
            assert globbed or ('scripts/' + name) in cmake, '%s/scripts/%s is not installed' % (pkg, name)


def _python_programs():
    """Every Python executable of a package's scripts/ or test/ tree (shebang names python)."""
    for pkg in PACKAGES:
        for sub in ('scripts', 'test'):
            for root, dirs, files in os.walk(os.path.join(WS, 'src', pkg, sub)):
                dirs[:] = [d for d in dirs if d != '__pycache__']
                for name in files:
                    path = os.path.join(root, name)
                    if name.endswith('.py') or not os.access(path, os.X_OK):
                        continue
                    with open(path, 'rb') as f:
                        first = f.readline()
                    if first.startswith(b'#!') and b'python' in first:
                        yield os.path.relpath(path, WS)


def test_every_python_program_compiles():
    """Node scripts without a .py suffix are imported by no pytest: a syntax error in one would
    only show when a launch file starts it."""
    programs = list(_python_programs())
    assert len(programs) > 20
    for rel in programs:
        with open(os.path.join(WS, rel)) as f:
            source = f.read()
        try:
            compile(source, rel, 'exec')
        except SyntaxError as exc:
            pytest.fail('%s does not compile: %s' % (rel, exc))


def _launch_nodes(args):
    import roslaunch.config
    import roslaunch.xmlloader
    config = roslaunch.config.ROSLaunchConfig()
    loader = roslaunch.xmlloader.XmlLoader()
    loader.load(os.path.join(WS, 'launch', 'platform.launch'), config, argv=['x'] + args, verbose=False)
    return config.nodes


@pytest.mark.parametrize('args', [[], ['sim:=false', 'rviz:=false', 'record:=false']])
def test_platform_launch_resolves_every_executable(args):
    import roslib.packages
    nodes = _launch_nodes(args)
    assert nodes
    for n in nodes:
        found = roslib.packages.find_node(n.package, n.type)
        assert found, 'node %s: executable %s/%s not found' % (n.name, n.package, n.type)


def test_sim_false_starts_no_simulator_and_switches_are_honoured():
    real = _launch_nodes(['sim:=false', 'rviz:=false', 'record:=false'])
    sim = _launch_nodes([])
    real_types = {n.type for n in real}
    assert not [t for t in real_types if 'sim' in t], real_types
    sim_types = {n.type for n in sim}
    assert {'rviz', 'recorder'} <= sim_types
    assert not {'rviz', 'recorder'} & real_types
    # both SARAS channels come from the same include (one node per side, same executable)
    sides = [n for n in sim if n.namespace.startswith('/mesa_')]
    assert {n.namespace.rstrip('/') for n in sides} >= {'/mesa_left', '/mesa_right'}


def test_sim_false_captures_the_endoscope_from_the_given_pipelines():
    """With the real hardware the endoscope comes from the capture nodelet (saras_drivers StereoCapture)
    in the visual feedback manager, fed by the pipelines given to platform.launch; never in simulation."""
    nodes = _launch_nodes(['sim:=false', 'rviz:=false', 'record:=false',
                           'endoscope_left_pipeline:=videotestsrc ! appsink',
                           'endoscope_right_pipeline:=/dev/video1'])
    cap = [n for n in nodes if n.namespace == '/endoscope/' and n.name == 'stereo_capture']
    assert cap, [(n.namespace, n.name) for n in nodes]
    assert 'saras_drivers/StereoCapture' in cap[0].args and '/visual_feedback_manager' in cap[0].args
    assert not [n for n in _launch_nodes([]) if n.name == 'stereo_capture']


def test_node_graph_lists_every_node_of_platform_launch():
    """docs/node_graph.md (captured from the running platform) and the README diagram are in sync
    with the launch files: every node started in simulation (no rviz, no recorder) appears."""
    with open(os.path.join(WS, 'docs', 'node_graph.md')) as f:
        graph = f.read()
    with open(os.path.join(WS, 'README.md')) as f:
        readme = f.read()
    for n in _launch_nodes(['rviz:=false', 'record:=false']):
        name = (n.namespace.rstrip('/') + '/' + n.name)
        assert '"%s"' % name in graph, '%s missing from docs/node_graph.md' % name
        assert '"%s"' % name in readme, '%s missing from the README node graph' % name


@pytest.mark.parametrize('pkg', PACKAGES)
def test_python_tests_are_registered_with_catkin(pkg):
    """A package with pytest files registers them with catkin's run_tests (saras_add_pytest), so
    `make test` runs them; the root pytest.ini runs only tests/."""
    test_dir = os.path.join(WS, 'src', pkg, 'test')
    has_pytest = os.path.isdir(test_dir) and any(
        f.startswith('test_') and f.endswith('.py') for f in os.listdir(test_dir))
    if not has_pytest:
        pytest.skip('%s has no pytest files' % pkg)
    with open(os.path.join(WS, 'src', pkg, 'CMakeLists.txt')) as f:
        cmake = f.read()
    assert re.search(r'saras_add_pytest\(\s*test\b', cmake), '%s: saras_add_pytest(test) missing' % pkg
