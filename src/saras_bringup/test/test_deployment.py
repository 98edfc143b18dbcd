"""Node -> machine graph and application links of a cluster run (saras_bringup.deployment)."""
from saras_bringup.deployment import application_links, machine_graph, machine_of, machines_html

ADDR = {'core_pc': '10.77.0.10', 'teleop_pc': '10.77.0.11', 'dvrk_pc': '10.77.0.12',
        'console_pc': '10.77.0.13', 'saras_left': '10.77.0.14'}


def test_machine_of_uses_the_uri_host():
    assert machine_of('http://10.77.0.12:40411/', ADDR) == 'dvrk_pc'
    assert machine_of('http://127.0.0.1:40411/', ADDR) == '?'


def test_graph_topics_between_machines():
    pubs = [('/dvrk/PSM1/position_cartesian_current', ['/dvrk/dvrk_sim']),
            ('/teleop/left/master_pose', ['/teleop/teleop_manager'])]
    subs = [('/dvrk/PSM1/position_cartesian_current', ['/colliding_regions', '/recorder']),
            ('/teleop/left/master_pose', ['/teleop/teleop_manager', '/recorder'])]
    uris = {'/dvrk/dvrk_sim': 'http://10.77.0.12:1/', '/colliding_regions': 'http://10.77.0.11:2/',
            '/recorder': 'http://10.77.0.10:3/', '/teleop/teleop_manager': 'http://10.77.0.11:4/'}
    g = machine_graph((pubs, subs, []), uris, ADDR)
    assert g['nodes']['/recorder'] == 'core_pc'
    assert g['machines']['dvrk_pc']['topics_out'] == {'/dvrk/PSM1/position_cartesian_current': ['core_pc', 'teleop_pc']}
    # a topic consumed on its own machine too: only the other machines are links
    assert g['machines']['teleop_pc']['topics_out'] == {'/teleop/left/master_pose': ['core_pc']}
    assert g['machines']['core_pc']['topics_in']['/teleop/left/master_pose'] == ['teleop_pc']
    assert '?' not in g['machines']
    html = dict(machines_html(g, [], {'dvrk_pc': {'skew_ms': -48.0, 'streams': {'/a': -48.0}}},
                              {'dvrk_pc': {'level': 1, 'message': 'offset +50.1 ms'}}))
    assert '-48.0 ms' in html['Machine dvrk_pc'] and '/dvrk/dvrk_sim' in html['Machine dvrk_pc']
    assert 'clock monitor: WARN offset +50.1 ms' in html['Machine dvrk_pc']
    assert 'clock monitor' not in html['Machine core_pc']


def test_application_links_follow_relays():
    params = {'touchball_console_sim': {'target_address': '10.77.0.13', 'target_port': 16000,
                                        'command_address': '10.77.0.13', 'command_port': 5016},
              'touchball_receiver': {'bind_address': '10.77.0.11', 'allowed_source': '10.77.0.13', 'command_port': 5006},
              'mesa_left': {'saras_arms_driver': {'host': '10.77.0.14', 'port': 5001}}}
    relays = [{'name': 'console_to_teleop', 'listen': '10.77.0.13:16000', 'target': '10.77.0.11:8888'},
              {'name': 'commands_to_console', 'listen': '10.77.0.13:5006', 'target': '10.77.0.13:5016'}]
    links = application_links(params, ADDR, relays)
    assert links[0] == {'from': 'console_pc', 'to': 'teleop_pc', 'protocol': 'udp', 'port': 8888,
                        'what': 'Touchball state packets', 'relay': 'console_to_teleop'}
    assert links[1]['from'] == 'teleop_pc' and links[1]['to'] == 'console_pc' and links[1]['relay'] == 'commands_to_console'
    assert links[2] == {'from': 'teleop_pc', 'to': 'saras_left', 'protocol': 'tcp', 'port': 5001,
                        'what': 'SARAS left arm Socket.IO', 'relay': ''}
