"""Which node runs on which machine, and which links join the machines (the cluster report).

ROS-free: ``machine_graph`` takes the master's system state and the nodes' XML-RPC URIs (a node
runs on the machine whose address its URI names, since every machine sets ROS_IP), and
``application_links`` takes the run's parameters (the console UDP stream and force commands, the
SARAS Socket.IO connections). ``machines_html`` renders one report section per machine.
"""
import html
from urllib.parse import urlparse


def machine_of(uri, addresses):
    """Role whose address is the host of ``uri`` ('?' when none)."""
    host = urlparse(uri).hostname or ''
    for role, addr in addresses.items():
        if addr == host:
            return role
    return '?'


def machine_graph(system_state, node_uris, addresses):
    """{'nodes': {node: role}, 'machines': {role: {'address', 'nodes', 'topics_out', 'topics_in'}}}.

    system_state: (publishers, subscribers, services) as the master's getSystemState returns them;
    topics_out[topic] = machines (other than this one) subscribing to a topic this machine
    publishes; topics_in[topic] = machines publishing a topic this machine subscribes to.
    """
    pubs, subs = system_state[0], system_state[1]
    nodes = {n: machine_of(u, addresses) for n, u in node_uris.items()}
    machines = {r: {'address': a, 'nodes': [], 'topics_out': {}, 'topics_in': {}} for r, a in addresses.items()}
    machines.setdefault('?', {'address': '?', 'nodes': [], 'topics_out': {}, 'topics_in': {}})
    for node, role in sorted(nodes.items()):
        machines[role]['nodes'].append(node)
    subscribers = {t: {nodes.get(n, '?') for n in ns} for t, ns in subs}
    for topic, ns in pubs:
        for src in sorted({nodes.get(n, '?') for n in ns}):
            dst = sorted(subscribers.get(topic, set()) - {src})
            if dst:
                machines[src]['topics_out'][topic] = dst
                for d in dst:
                    machines[d]['topics_in'].setdefault(topic, []).append(src)
    if not machines['?']['nodes']:
        del machines['?']
    return {'nodes': nodes, 'machines': machines}


def _param(params, path):
    node = params
    for key in path.strip('/').split('/'):
        if not isinstance(node, dict) or key not in node:
            return None
        node = node[key]
    return node


def _role(addresses, addr):
    for role, a in addresses.items():
        if a == addr:
            return role
    return addr


def application_links(params, addresses, relays=()):
    """Non-ROS links from the run's parameters: list of dicts (from, to, protocol, port, what).

    relays: netem_relay link dicts (name, listen, target); a link that goes to a relay's listen
    address is reported to the relay's target, with the relay's name.
    """
    via = {r['listen']: r for r in relays}
    links = []

    def add(src_role, host, port, proto, what):
        if host is None or port is None:
            return
        relay = via.get('%s:%s' % (host, port))
        if relay:
            host, port = relay['target'].rsplit(':', 1)
        links.append({'from': src_role, 'to': _role(addresses, host), 'protocol': proto, 'port': int(port),
                      'what': what, 'relay': relay['name'] if relay else ''})

    console = _param(params, '/touchball_console_sim')
    if isinstance(console, dict):
        add(_role(addresses, console.get('command_address')), console.get('target_address'),
            console.get('target_port'), 'udp', 'Touchball state packets')
    recv = _param(params, '/touchball_receiver')
    if isinstance(recv, dict):
        add(_role(addresses, recv.get('bind_address')), recv.get('allowed_source'), recv.get('command_port'),
            'udp', 'Touchball force commands')
    for side in ('left', 'right'):
        drv = _param(params, '/mesa_%s/saras_arms_driver' % side)
        if isinstance(drv, dict):
            add('teleop_pc', drv.get('host'), drv.get('port'), 'tcp', 'SARAS %s arm Socket.IO' % side)
    return links


def machines_html(graph, links, skew=None, clocks=None):
    """One HTML block per machine: its nodes, its application links, the topics it sends to and
    receives from the other machines, the stamp skew of its streams (bag_check --machines) and
    the clock monitor's status of it (clocks: {machine: {level, message}})."""
    out = []
    for role, m in sorted(graph['machines'].items()):
        rows = ['<p>address <code>%s</code>, %d nodes: %s</p>' % (
            html.escape(m['address']), len(m['nodes']), ', '.join('<code>%s</code>' % html.escape(n)
                                                                  for n in m['nodes']))]
        mine = [lk for lk in links if role in (lk['from'], lk['to'])]
        if mine:
            rows.append('<table><tr><th>link</th><th>protocol/port</th><th>what</th><th>relay</th></tr>%s</table>' % ''.join(
                '<tr><td>%s &rarr; %s</td><td>%s %s</td><td>%s</td><td>%s</td></tr>' % tuple(
                    html.escape(str(v)) for v in (lk['from'], lk['to'], lk['protocol'], lk['port'],
                                                  lk['what'], lk['relay'] or '-')) for lk in mine))
        for key, label in (('topics_out', 'sends (TCPROS) to'), ('topics_in', 'receives (TCPROS) from')):
            if m[key]:
                rows.append('<p>%d topics %s other machines: %s</p>' % (len(m[key]), label, '; '.join(
                    '<code>%s</code> %s %s' % (html.escape(t), '&rarr;' if key == 'topics_out' else '&larr;',
                                               html.escape(', '.join(r))) for t, r in sorted(m[key].items()))))
        if skew and role in skew:
            rows.append('<p>stamp skew of its recorded streams (receive time - header stamp, lowest 5th '
                        'percentile): %.1f ms over %d streams</p>'
                        % (skew[role]['skew_ms'], len(skew[role]['streams'])))
        if clocks and role in clocks:
            rows.append('<p>clock monitor: %s %s</p>' % (
                ('OK', 'WARN', 'ERROR', 'STALE')[min(3, int(clocks[role]['level']))],
                html.escape(clocks[role]['message'])))
        out.append(('Machine %s' % role, '\n'.join(rows)))
    return out
