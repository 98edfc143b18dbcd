"""CPU share of every process of a running platform, from ``/proc`` (Linux), against a budget.

Two samples of a process tree (``sample``) taken at the start and the end of a recording give each
process's CPU time over that window (``shares``): user + system time of the process, in percent of
one core. Processes are named as ROS names them: ``__name:=`` of the command line in the namespace of
its ``ROS_NAMESPACE``; a helper process without a name (e.g. the ``rosbag record`` child of the
recorder) counts for its nearest named ancestor; roslaunch and the master by their programs.
``budget_rows`` classifies the processes (simulators vs product) and checks each against the budgets of
``config/cpu_budget.yaml``. Threads of a nodelet manager can belong to another row (``thread_rows``:
{process: {thread-name prefix: row}}, thread name = ``/proc/PID/task/TID/comm``); their CPU is moved
from the host process's row to that row:

* ``simulator_threads`` ({process: prefix}): a simulator's threads in a product process (the simulated
  endoscope renders inside the visual-feedback nodelet manager, zero-copy like the real capture
  nodelet) form a row of their own, ``<process> [<prefix>* threads]``, counted as a simulator;
* ``attributed_threads`` ({process: {prefix: row}}): threads doing another process's work (the
  recorder's in-process bag writer ``stream_bag`` in the teleoperation manager) count for that row,
  shown as ``<row> (+ <prefix> in <process>)`` and checked against ``<row>``'s budget.

Reading /proc costs a few milliseconds per sample: nothing runs in between.
"""
import os
import time

from saras_common import procfs

CLK_TCK = procfs.CLK_TCK
LAUNCHERS = ('roslaunch', 'rosmaster', 'roscore')   # named by their program; their children by their own


class BudgetError(ValueError):
    """A malformed budget file."""


def _own_name(pid):
    """The ROS name of a process (``/ns/name``), its program for roslaunch/rosmaster, else None."""
    argv = [a.decode(errors='replace') for a in procfs.cmdline(pid)]
    for a in argv:
        if a.startswith('__name:='):
            ns = procfs.environ(pid).get(b'ROS_NAMESPACE', b'').decode(errors='replace')
            return '/' + '/'.join(p for p in ns.split('/') + [a[len('__name:='):]] if p)
    return next((prog for prog in LAUNCHERS if any(os.path.basename(a) == prog for a in argv[:3])), None)


def thread_row(name, prefix):
    """Name of the row of a process's simulator threads (see the module doc)."""
    return '%s [%s* threads]' % (name, prefix)


def sample(roots, split=None):
    """CPU ticks of every process in the trees under ``roots`` (pids): {'wall': s, 'procs': [...]}.
    ``split``: {process name: {thread-name prefix: row}} (``thread_rows`` of :func:`parse_budget`):
    the ticks of those threads are an entry of that row, taken off the process's own."""
    split = split or {}
    stats = {}
    for pid in procfs.pids():
        st = procfs.stat(pid)
        if st is not None:
            stats[pid] = st
    children = {}
    for pid, (ppid, _, _) in stats.items():
        children.setdefault(ppid, []).append(pid)
    procs, stack = [], [(r, None) for r in roots if r in stats]
    while stack:
        pid, parent_label = stack.pop()
        label = _own_name(pid) or parent_label or procfs.comm(pid)
        _, ticks, start = stats[pid]
        threads = procfs.threads(pid) if label in split else {}
        apart = {}
        for prefix, row in split.get(label, {}).items():
            apart[row] = apart.get(row, 0) + sum(t for n, t in threads.items() if n.startswith(prefix))
        for row, row_ticks in sorted(apart.items()):
            ticks -= row_ticks
            procs.append({'pid': pid, 'start': start, 'name': row, 'ticks': row_ticks})
        procs.append({'pid': pid, 'start': start, 'name': label, 'ticks': ticks})
        inherited = None if label == 'roslaunch' else label   # roslaunch's children are the nodes
        stack.extend((c, inherited) for c in children.get(pid, ()))
    return {'wall': time.monotonic(), 'procs': procs}


def shares(before, after):
    """{name: percent of one core} over the window between two samples (processes started in the
    window count from their start; processes that ended in it are missing)."""
    wall = after['wall'] - before['wall']
    if wall <= 0:
        raise ValueError('the second sample must be later than the first')
    old = {(p['pid'], p['start'], p['name']): p['ticks'] for p in before['procs']}
    out = {}
    for p in after['procs']:
        delta = p['ticks'] - old.get((p['pid'], p['start'], p['name']), 0)
        out[p['name']] = out.get(p['name'], 0.0) + 100.0 * delta / CLK_TCK / wall
    return out


def _ros_name(value):
    return isinstance(value, str) and value.startswith('/')


def _attributed(data):
    """``attributed_threads`` {process: {prefix: row}} validated, and the display names of their rows."""
    attributed = data.get('attributed_threads', {})
    if not isinstance(attributed, dict) or not all(
            _ros_name(k) and isinstance(v, dict) and v and all(isinstance(p, str) and p and _ros_name(r)
                                                               for p, r in v.items())
            for k, v in attributed.items()):
        raise BudgetError('attributed_threads: ROS name -> {non-empty thread-name prefix: ROS name of its row}')
    shown = {}
    for process, prefixes in sorted(attributed.items()):
        for prefix, row in sorted(prefixes.items()):
            shown.setdefault(row, []).append('%s in %s' % (prefix, process))
    return attributed, {row: '%s (+ %s)' % (row, ', '.join(parts)) for row, parts in shown.items()}


def parse_budget(data):
    """Validate a budget file's content: {'simulators': [names], 'budgets': {name: %}, 'product_total': %,
    'simulator_threads': {process name: thread-name prefix},
    'attributed_threads': {process name: {thread-name prefix: row}}}; adds 'thread_rows' (both as
    {process: {prefix: row}}, for :func:`sample`) and 'shown' ({row: its name in the table})."""
    if not isinstance(data, dict):
        raise BudgetError('the budget file must be a mapping')
    sims = data.get('simulators', [])
    budgets = data.get('budgets', {})
    total = data.get('product_total')
    threads = data.get('simulator_threads', {})
    if not isinstance(threads, dict) or not all(
            _ros_name(k) and isinstance(v, str) and v for k, v in threads.items()):
        raise BudgetError('simulator_threads: ROS name -> non-empty thread-name prefix')
    attributed, shown = _attributed(data)
    if not isinstance(sims, list) or not all(isinstance(s, str) and s.startswith('/') for s in sims):
        raise BudgetError('simulators: a list of ROS names (/ns/name)')
    if not isinstance(budgets, dict) or not all(
            isinstance(v, (int, float)) and 0 < v <= 100 for v in budgets.values()):
        raise BudgetError('budgets: ROS name -> percent of one core in (0, 100]')
    if not isinstance(total, (int, float)) or not 0 < total <= 200:
        raise BudgetError('product_total: percent of one core in (0, 200]')
    sims = list(sims) + [thread_row(k, v) for k, v in threads.items()]
    rows = {k: {v: thread_row(k, v)} for k, v in threads.items()}
    for process, prefixes in attributed.items():
        rows.setdefault(process, {}).update(prefixes)
    return {'simulators': sims, 'budgets': dict(budgets), 'product_total': float(total),
            'simulator_threads': dict(threads), 'attributed_threads': attributed, 'thread_rows': rows,
            'shown': shown}


def budget_rows(cpu, budget):
    """Rows (name, kind, percent, budget or None, ok) sorted by kind then cost, and the product total row.
    A row with attributed threads is named as in ``budget['shown']``, its budget is its process's."""
    rows = []
    for name, pct in cpu.items():
        kind = 'simulator' if name in budget['simulators'] else 'product'
        limit = budget['budgets'].get(name)
        rows.append((budget.get('shown', {}).get(name, name), kind, pct, limit, limit is None or pct <= limit))
    rows.sort(key=lambda r: (r[1] != 'product', -r[2]))
    product = sum(r[2] for r in rows if r[1] == 'product')
    total = ('product processes together', 'product', product, budget['product_total'],
             product <= budget['product_total'])
    return rows, total


def table_text(rows, total):
    """Plain-text table of :func:`budget_rows` (the demo prints it and the report shows it)."""
    width = max([40] + [len(r[0]) for r in rows])
    lines = ['%-*s %-9s %8s %8s  %s' % (width, 'process', 'kind', 'CPU [%]', 'budget', 'verdict')]
    for name, kind, pct, limit, ok in list(rows) + [total]:
        lines.append('%-*s %-9s %8.1f %8s  %s' % (width, name, kind, pct, '-' if limit is None else '%.0f' % limit,
                                                '' if limit is None else ('ok' if ok else 'OVER')))
    return '\n'.join(lines)
