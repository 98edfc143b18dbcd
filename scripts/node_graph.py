#!/usr/bin/env python3
"""Write the platform's node/topic graph (Mermaid) from a RUNNING ROS master.

  scripts/node_graph.py OUT.md      (ROS_MASTER_URI must point at the running platform)
The demo runs it, and docs/node_graph.md in the repository is such a capture; tests/test_workspace.py
checks that every node platform.launch starts appears in it, so the README diagram stays in sync.
"""
import re
import sys

import rosgraph.masterapi

IGNORED_TOPICS = ('/rosout', '/rosout_agg', '/clock', '/tf', '/tf_static', '/diagnostics', '/diagnostics_agg',
                  '/diagnostics_toplevel_state')
IGNORED_NODES = ('/rosout', '/rostopic', '/rosnode', '/wait_ready', '/recorder', '/node_graph')


def ident(name):
    return 'n_' + re.sub(r'[^A-Za-z0-9_]', '_', name.strip('/'))


def main(out_path):
    master = rosgraph.masterapi.Master('/node_graph')
    pubs, subs, _ = master.getSystemState()
    # nodelet managers: '<manager>/bond' connects a manager with its loader nodes (one per nodelet);
    # the nodelets' topics are registered under the manager, so the loaders are drawn inside it
    members = {}
    for topic, ns in list(pubs) + list(subs):
        if topic.endswith('/bond'):
            members.setdefault(topic[:-len('/bond')], set()).update(ns)
    groups = {m: sorted(ns - {m}) for m, ns in members.items() if m in ns}
    edges = {}
    internal = {}
    sub_map = {t: [n for n in ns if not n.startswith(IGNORED_NODES)] for t, ns in subs}
    nodes = set()
    for topic, publishers in pubs:
        nodes.update(p for p in publishers if not p.startswith(IGNORED_NODES))
        if topic in IGNORED_TOPICS or topic.endswith('/bond'):
            continue
        for p in publishers:
            if p.startswith(IGNORED_NODES):
                continue
            nodes.add(p)
            for s in sub_map.get(topic, []):
                if s == p and p in groups:
                    internal.setdefault(p, []).append(topic)
                if s != p:
                    nodes.add(s)
                    edges.setdefault((p, s), []).append(topic)
    for topic, ns in sub_map.items():
        nodes.update(ns)
    nodes.discard('/rosout')
    lines = ['# Platform node graph', '',
             'Captured from the running simulated platform (`make demo`, scripts/node_graph.py).',
             'Edges are topics; `/tf`, `/tf_static`, `/diagnostics*` and /rosout are omitted',
             '(every node uses TF; see docs/interfaces.md for frames). A nodelet manager is drawn as a box',
             'holding its nodelets (their loader node names); its topics, including the zero-copy',
             'intra-process ones (self edge), are registered under the manager.', '',
             '```mermaid', 'flowchart LR']
    grouped = set()
    for m, loaders in sorted(groups.items()):
        lines.append('  subgraph %s_group["%s (nodelet manager)"]' % (ident(m), m))
        for n in [m] + loaders:
            lines.append('    %s["%s"]' % (ident(n), n))
            grouped.add(n)
        lines.append('  end')
    for n in sorted(nodes - grouped):
        lines.append('  %s["%s"]' % (ident(n), n))
    for (p, s), topics in sorted(edges.items()):
        label = '<br/>'.join(sorted(topics)[:4]) + ('<br/>+%d more' % (len(topics) - 4) if len(topics) > 4 else '')
        lines.append('  %s -->|"%s"| %s' % (ident(p), label, ident(s)))
    for m, topics in sorted(internal.items()):
        topics = sorted(set(topics))
        label = '<br/>'.join(topics[:4]) + ('<br/>+%d more' % (len(topics) - 4) if len(topics) > 4 else '')
        lines.append('  %s -->|"intra-process: %s"| %s' % (ident(m), label, ident(m)))
    lines.append('```')
    lines.append('')
    lines.append('Nodes: %d, publisher→subscriber pairs: %d.' % (len(nodes), len(edges)))
    with open(out_path, 'w') as f:
        f.write('\n'.join(lines) + '\n')
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1]))
