#!/usr/bin/env python3
"""Capture which node runs on which machine of a RUNNING cluster, and the links between machines.

  scripts/cluster/machine_graph.py CLUSTER_ENV PARAMS_YAML OUT.json [LINKS_YAML ...]
CLUSTER_ENV: <run>/cluster.env of scripts/cluster/netns.sh (SARAS_ADDR_<role>=address);
PARAMS_YAML: `rosparam dump` of the run; LINKS_YAML: netem_relay link files in the path.
Writes {"graph": saras_bringup.deployment.machine_graph, "links": application_links, "clocks":
{machine: {level, message, offset_ms}} (the clock monitor's last /diagnostics status per machine)};
make_report --machines and bag_check --machines read it.
"""
import json
import sys
import threading

import rosgraph.masterapi
import yaml

from saras_bringup.deployment import application_links, machine_graph


def read_addresses(path):
    addresses = {}
    with open(path) as stream:
        for line in stream:
            if line.startswith('SARAS_ADDR_') and '=' in line:
                key, value = line.strip().split('=', 1)
                addresses[key[len('SARAS_ADDR_'):]] = value
    return addresses


def clock_statuses(timeout_s=15.0):
    """The clock monitor's latest status per machine seen on /diagnostics within timeout_s."""
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray
    found, done = {}, threading.Event()

    def callback(msg):
        for st in msg.status:
            if st.name.startswith('clock_monitor: '):
                values = {kv.key: kv.value for kv in st.values}
                found[st.name[len('clock_monitor: '):]] = {
                    'level': int.from_bytes(st.level, 'little') if isinstance(st.level, bytes) else int(st.level),
                    'message': st.message, 'offset_ms': values.get('offset_ms')}
        if len(found) >= 5:
            done.set()

    rospy.init_node('machine_graph', anonymous=True, disable_signals=True)
    sub = rospy.Subscriber('/diagnostics', DiagnosticArray, callback, queue_size=50)
    done.wait(timeout_s)
    sub.unregister()
    return dict(found)


def main(env_path, params_path, out_path, *links_paths):
    addresses = read_addresses(env_path)
    master = rosgraph.masterapi.Master('/machine_graph')
    state = master.getSystemState()
    names = {n for group in state for _, ns in group for n in ns}
    uris = {}
    for name in sorted(names):
        try:
            uris[name] = master.lookupNode(name)
        except rosgraph.masterapi.Error:
            pass  # gone since getSystemState
    with open(params_path) as stream:
        params = yaml.safe_load(stream) or {}
    relays = []
    for path in links_paths:
        with open(path) as stream:
            relays += (yaml.safe_load(stream) or {}).get('links', [])
    graph = machine_graph(state, uris, addresses)
    with open(out_path, 'w') as stream:
        json.dump({'graph': graph, 'links': application_links(params, addresses, relays),
                   'clocks': clock_statuses()}, stream, indent=1)
    for role, m in sorted(graph['machines'].items()):
        print('%-12s %-12s %3d nodes, sends %d topics, receives %d topics' % (
            role, m['address'], len(m['nodes']), len(m['topics_out']), len(m['topics_in'])))
    return 0


if __name__ == '__main__':
    if len(sys.argv) < 4:
        sys.stderr.write(__doc__)
        sys.exit(2)
    sys.exit(main(*sys.argv[1:]))
