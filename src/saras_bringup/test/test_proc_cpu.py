"""proc_cpu: per-process CPU from /proc, named as ROS names them, checked against a budget."""
import os
import signal
import subprocess
import sys
import time

import pytest

from saras_bringup import proc_cpu

BUSY = 'import time\nt = time.process_time()\nwhile time.process_time() - t < 0.6: pass\ntime.sleep(30)'
BUDGET = {'simulators': ['/sim'], 'budgets': {'/ns/busy': 5}, 'product_total': 60}


def test_a_busy_named_node_and_its_unnamed_child():
    env = dict(os.environ, ROS_NAMESPACE='/ns')
    parent = subprocess.Popen(['/bin/sh', '-c', 'sleep 30 & exec %s -c "$0" __name:=busy' % sys.executable, BUSY],
                              env=env, start_new_session=True)
    try:
        time.sleep(0.3)
        before = proc_cpu.sample([parent.pid])
        time.sleep(1.5)
        after = proc_cpu.sample([parent.pid])
    finally:
        os.killpg(parent.pid, signal.SIGKILL)
        parent.wait()
    assert sorted(p['name'] for p in after['procs']) == ['/ns/busy', '/ns/busy']   # python + its sleep
    cpu = proc_cpu.shares(before, after)
    assert 15.0 < cpu['/ns/busy'] < 110.0           # it burnt CPU for part of the window
    assert proc_cpu.shares(after, after.copy() | {'wall': after['wall'] + 1})['/ns/busy'] == 0.0


NAMED_THREAD = '''import ctypes, sys, threading, time
def burn():
    ctypes.CDLL(None).prctl(15, sys.argv[1].encode(), 0, 0, 0)   # PR_SET_NAME
    t = time.thread_time()
    while time.thread_time() - t < 0.6: pass
    time.sleep(30)
threading.Thread(target=burn, daemon=True).start()
time.sleep(30)'''


def sample_window(procs, budget):
    """Two samples 1.5 s apart of the started processes ([argv]) with ``budget``'s thread rows."""
    started = [subprocess.Popen(argv, start_new_session=True) for argv in procs]
    try:
        time.sleep(0.2)
        before = proc_cpu.sample([p.pid for p in started], budget['thread_rows'])
        time.sleep(1.5)
        after = proc_cpu.sample([p.pid for p in started], budget['thread_rows'])
    finally:
        for p in started:
            os.killpg(p.pid, signal.SIGKILL)
            p.wait()
    return proc_cpu.shares(before, after)


def test_a_simulator_thread_of_a_product_process_is_counted_apart():
    budget = proc_cpu.parse_budget(dict(BUDGET, simulator_threads={'/host': 'endoscope_sim'}))
    cpu = sample_window([[sys.executable, '-c', NAMED_THREAD, 'endoscope_sim_l', '__name:=host']], budget)
    row = proc_cpu.thread_row('/host', 'endoscope_sim')
    assert 15.0 < cpu[row] < 110.0                  # the named thread burnt CPU in the window
    assert cpu['/host'] < 5.0                       # the rest of the process slept
    rows, total = proc_cpu.budget_rows(cpu, budget)
    assert dict((r[0], r[1]) for r in rows)[row] == 'simulator'
    assert total[2] == pytest.approx(cpu['/host'])


ATTRIBUTED = dict(BUDGET, budgets={'/rec': 5, '/host': 50}, attributed_threads={'/host': {'stream_bag': '/rec'}})


def test_a_thread_working_for_another_process_counts_for_its_row():
    budget = proc_cpu.parse_budget(ATTRIBUTED)
    sleeper = [sys.executable, '-c', 'import time; time.sleep(30)', '__name:=rec']
    cpu = sample_window([[sys.executable, '-c', NAMED_THREAD, 'stream_bag', '__name:=host'], sleeper], budget)
    assert 15.0 < cpu['/rec'] < 110.0               # the host's stream_bag thread, moved to the recorder
    assert cpu['/host'] < 5.0
    rows, total = proc_cpu.budget_rows(cpu, budget)
    row = [r for r in rows if r[0].startswith('/rec')][0]
    assert row[0] == '/rec (+ stream_bag in /host)' and row[1] == 'product'
    assert row[3] == 5 and row[4] is False          # the recorder's budget, exceeded by the thread
    assert '/rec (+ stream_bag in /host)' in proc_cpu.table_text(rows, total)


def test_attributed_threads_move_ticks_between_rows():
    budget = proc_cpu.parse_budget(dict(ATTRIBUTED, simulator_threads={'/host': 'sim'}))
    assert budget['thread_rows'] == {'/host': {'sim': '/host [sim* threads]', 'stream_bag': '/rec'}}
    assert budget['shown'] == {'/rec': '/rec (+ stream_bag in /host)'}
    # the manager (pid 1) hosts the writer thread of the recorder (pid 2): 0.5 s of it in a 1 s window
    before = {'wall': 0.0, 'procs': [{'pid': 1, 'start': 5, 'name': '/rec', 'ticks': 0},
                                     {'pid': 1, 'start': 5, 'name': '/host', 'ticks': 0},
                                     {'pid': 2, 'start': 6, 'name': '/rec', 'ticks': 0}]}
    after = {'wall': 1.0, 'procs': [{'pid': 1, 'start': 5, 'name': '/rec', 'ticks': proc_cpu.CLK_TCK // 2},
                                    {'pid': 1, 'start': 5, 'name': '/host', 'ticks': proc_cpu.CLK_TCK // 10},
                                    {'pid': 2, 'start': 6, 'name': '/rec', 'ticks': proc_cpu.CLK_TCK // 10}]}
    cpu = proc_cpu.shares(before, after)
    assert cpu == pytest.approx({'/rec': 60.0, '/host': 10.0})
    rows, total = proc_cpu.budget_rows(cpu, budget)
    assert [(r[0], r[3], r[4]) for r in rows] == [('/rec (+ stream_bag in /host)', 5, False), ('/host', 50, True)]
    assert total[2] == pytest.approx(70.0)


def test_unnamed_children_count_for_their_named_parent():
    before = {'wall': 0.0, 'procs': [{'pid': 1, 'start': 5, 'name': '/rec', 'ticks': 0},
                                     {'pid': 2, 'start': 6, 'name': '/rec', 'ticks': 0}]}
    after = {'wall': 2.0, 'procs': [{'pid': 1, 'start': 5, 'name': '/rec', 'ticks': proc_cpu.CLK_TCK // 2},
                                    {'pid': 2, 'start': 6, 'name': '/rec', 'ticks': proc_cpu.CLK_TCK // 2},
                                    {'pid': 3, 'start': 9, 'name': '/new', 'ticks': proc_cpu.CLK_TCK}]}
    cpu = proc_cpu.shares(before, after)
    assert cpu['/rec'] == pytest.approx(50.0)
    assert cpu['/new'] == pytest.approx(50.0)      # started in the window: counted from its start


def test_a_reused_pid_is_a_new_process():
    before = {'wall': 0.0, 'procs': [{'pid': 1, 'start': 5, 'name': '/a', 'ticks': 10 ** 6}]}
    after = {'wall': 1.0, 'procs': [{'pid': 1, 'start': 7, 'name': '/a', 'ticks': proc_cpu.CLK_TCK // 10}]}
    assert proc_cpu.shares(before, after)['/a'] == pytest.approx(10.0)


def test_budget_rows_and_verdicts():
    budget = proc_cpu.parse_budget(BUDGET)
    rows, total = proc_cpu.budget_rows({'/ns/busy': 7.0, '/other': 3.0, '/sim': 50.0}, budget)
    assert [r[0] for r in rows] == ['/ns/busy', '/other', '/sim']
    assert rows[0][4] is False and rows[1][4] is True and rows[2][1] == 'simulator'
    assert total[2] == pytest.approx(10.0) and total[4] is True
    text = proc_cpu.table_text(rows, total)
    assert 'OVER' in text and 'product processes together' in text


@pytest.mark.parametrize('bad', [
    [], {'simulators': 'x', 'budgets': {}, 'product_total': 60},
    {'simulators': [], 'budgets': {'/a': 0}, 'product_total': 60},
    {'simulators': [], 'budgets': {'/a': 'ten'}, 'product_total': 60},
    {'simulators': [], 'budgets': {}, 'product_total': None},
    {'simulators': [], 'budgets': {}, 'product_total': 60, 'simulator_threads': {'/a': ''}},
    {'simulators': [], 'budgets': {}, 'product_total': 60, 'simulator_threads': ['/a']},
    dict(BUDGET, attributed_threads={'/a': 'stream_bag'}),
    dict(BUDGET, attributed_threads={'/a': {}}),
    dict(BUDGET, attributed_threads={'/a': {'': '/rec'}}),
    dict(BUDGET, attributed_threads={'/a': {'stream_bag': 'rec'}}),
    dict(BUDGET, attributed_threads={'a': {'stream_bag': '/rec'}}),
    dict(BUDGET, attributed_threads=['/a'])])
def test_bad_budget_files_are_refused(bad):
    with pytest.raises(proc_cpu.BudgetError):
        proc_cpu.parse_budget(bad)


def test_the_shipped_budget_is_valid():
    import yaml
    path = os.path.join(os.path.dirname(__file__), '..', 'config', 'cpu_budget.yaml')
    budget = proc_cpu.parse_budget(yaml.safe_load(open(path)))
    assert budget['budgets']['/teleop/teleop_manager'] == 12 and budget['product_total'] == 60
    assert budget['thread_rows']['/teleop/teleop_manager'] == {'stream_bag': '/recorder'}
    assert budget['shown']['/recorder'] == '/recorder (+ stream_bag in /teleop/teleop_manager)'
