#!/usr/bin/env python3
"""Fault suite helpers (scripts/faults/run.sh): probe, injection, analysis.

  faults.py probe OUT          record what the faults are judged on into OUT/*.csv until SIGINT:
                               set-points and measured poses of both arms, collision distances,
                               ERROR/STALE statuses on /diagnostics (keeps recording after a master
                               loss over its existing connections); and be the operator: press the
                               clutch of both devices for 0.2 s every 4 s (OUT/clutch.csv)
  faults.py pid NODE           PID of a ROS node (asked over its own XML-RPC API)
  faults.py wait-link-restart OUT T0 S   time a restarted receiver first reports (counters reset)
  faults.py spoof-force SIDE S publish 1e6 N on /mesa_SIDE/contact_force at 60 Hz for S seconds
  faults.py spoof-target SIDE S publish zero-stamp targets 2 cm deeper at 500 Hz for S seconds
  faults.py analyse OUT        judge every fault of OUT/events.csv; table on stdout and OUT/faults.md;
                               exit 1 if an expectation is violated
Times are wall-clock seconds (time.time()); all processes run on this host.
"""
import bisect
import csv
import math
import os
import sys
import time

SIDES = ('left', 'right')


# ---------------------------------------------------------------------------------------- ROS side
def probe(out):
    import rospy
    from diagnostic_msgs.msg import DiagnosticArray
    from geometry_msgs.msg import PoseStamped
    from saras_msgs.msg import CollisionReport, HapticDeviceState
    from std_msgs.msg import Float64
    rospy.init_node('faults_probe', disable_signals=True)
    files = {}

    def writer(name):
        if name not in files:
            files[name] = csv.writer(open(os.path.join(out, name + '.csv'), 'w', buffering=1))
        return files[name]

    def pose_cb(name):
        def cb(m):
            p = m.pose.position
            writer(name).writerow(('%.6f' % time.time(), '%.6f' % m.header.stamp.to_sec(),
                                   '%.6f' % p.x, '%.6f' % p.y, '%.6f' % p.z))
        return cb

    for side in SIDES:
        rospy.Subscriber('/mesa_%s/target_pose' % side, PoseStamped, pose_cb('target_' + side), queue_size=200)
        rospy.Subscriber('/mesa_%s/ee_pose' % side, PoseStamped, pose_cb('ee_' + side), queue_size=200)

    def on_collision(m):
        d = dict((t.tool, t.distance) for t in m.tools)
        writer('collision').writerow(('%.6f' % time.time(), d.get('mesa_left', float('nan')),
                                      d.get('mesa_right', float('nan'))))

    def on_diag(m):
        for s in m.status:
            if s.level >= 2:
                writer('diag').writerow(('%.6f' % time.time(), s.level, s.name, s.message))
            if s.name.endswith('console link'):      # the receiver's counters (packet faults)
                v = dict((kv.key, kv.value) for kv in s.values)
                writer('link').writerow(['%.6f' % time.time(), s.level, v.get('packets received', ''),
                                         v.get('rejected datagrams', '')] +
                                        ['%s=%s' % (k[9:], x) for k, x in sorted(v.items())
                                         if k.startswith('rejected ') and k != 'rejected datagrams' and x != '0'])

    def on_energy(name):
        def cb(m):
            writer(name).writerow(('%.6f' % time.time(), '%.9f' % m.data))
        return cb

    for tank in ('master', 'slave'):
        rospy.Subscriber('/teleop/tank_%s/energy' % tank, Float64, on_energy('tank_' + tank), queue_size=200)
    rospy.Subscriber('/collision/report', CollisionReport, on_collision, queue_size=10)
    rospy.Subscriber('/diagnostics', DiagnosticArray, on_diag, queue_size=50)
    clutch = dict((side, rospy.Publisher('/touchball/%s/state' % side, HapticDeviceState, queue_size=10))
                  for side in SIDES)
    try:
        while True:
            time.sleep(3.8)
            writer('clutch').writerow(('%.6f' % time.time(),))
            for _ in range(10):          # pressed 0.2 s; the receiver's own states say released
                for side in SIDES:
                    m = HapticDeviceState(device=side, clutch=True)
                    m.header.stamp = rospy.Time.now()
                    clutch[side].publish(m)
                time.sleep(0.02)
    except KeyboardInterrupt:
        pass


def wait_link_restart(out, t0, timeout):
    """Print the time the probe first sees a restarted receiver's counters (received > 0, lower than
    before t0) on /diagnostics; exit 1 after timeout s. Its log lines cannot tell: a nodelet loader's
    output is block-buffered."""
    end = time.time() + timeout
    while time.time() < end:
        rows = [(float(x[0]), int(x[2])) for x in load(out, 'link') if x[2]]
        before = [n for t, n in rows if t <= t0]
        for t, n in rows:
            if t > t0 and before and 0 < n < before[-1]:
                print('%.6f' % t)
                return 0
        time.sleep(0.5)
    return 1


def node_pid(name):
    import rosgraph
    import xmlrpc.client
    uri = rosgraph.Master('/faults').lookupNode(name)
    code, _, pid = xmlrpc.client.ServerProxy(uri).getPid('/faults')
    print(pid)


def spoof(kind, side, seconds):
    import rospy
    from geometry_msgs.msg import PoseStamped, Twist
    rospy.init_node('faults_spoof_%s' % kind.replace('-', '_'), anonymous=True)
    stamp_file = os.environ.get('FAULTS_SPOOF_TIMES')
    if kind == 'force':
        pub, rate = rospy.Publisher('/mesa_%s/contact_force' % side, Twist, queue_size=10), 60.0
    else:
        pub, rate = rospy.Publisher('/mesa_%s/target_pose' % side, PoseStamped, queue_size=10), 500.0
        ee = rospy.wait_for_message('/mesa_%s/ee_pose' % side, PoseStamped, timeout=5.0)
    time.sleep(0.5)                      # connections
    start = time.time()
    end = start + seconds
    while time.time() < end:
        if kind == 'force':
            m = Twist()
            m.linear.z = 1e6
        else:
            m = PoseStamped()            # header.stamp zero
            m.header.frame_id = 'mesa_%s/sbs_world' % side
            m.pose = ee.pose
            m.pose.position.z = ee.pose.position.z - 0.02
        pub.publish(m)
        time.sleep(1.0 / rate)
    if stamp_file:
        with open(stamp_file, 'w') as f:
            f.write('%.6f %.6f\n' % (start, time.time()))


# ---------------------------------------------------------------------------------------- analysis
def load(out, name):
    path = os.path.join(out, name + '.csv')
    if not os.path.exists(path):
        return []
    with open(path) as f:
        return [r for r in csv.reader(f) if r]


def poses(out, name, zero_stamp=None):
    rows = []
    for r in load(out, name):
        if zero_stamp is not None and (float(r[1]) == 0.0) != zero_stamp:
            continue
        rows.append((float(r[0]), (float(r[2]), float(r[3]), float(r[4]))))
    return rows


def _times(rows):
    key = id(rows)
    if key not in _TIMES:
        _TIMES[key] = (rows, [r[0] for r in rows])
    return _TIMES[key][1]


_TIMES = {}
TANK_STEP_J = 1e-3  # [J] energy a tank may gain between its last published sample and its death
SPEED_LIMIT = 0.0505  # [m/s] 50 mm/s, with 1 % for the arithmetic of speeds from sample pairs
SPOOF_LAG = 0.5     # [s] how far back a real set-point still counts as the arm's path


def window(rows, a, b):
    ts = _times(rows)
    return rows[bisect.bisect_left(ts, a):bisect.bisect_left(ts, b)]


def at(rows, t):
    """Last sample at or before t (None if none)."""
    i = bisect.bisect_right(_times(rows), t)
    return rows[i - 1] if i else None


def hold_time(ee, t_fault, t_end, tol=0.0005):
    """Seconds from the fault until the arm stays within tol of where it is (None: never holds)."""
    w = window(ee, t_fault, t_end)
    if not w:
        return None
    # scan backwards: the earliest sample from which every later one stays within tol of it
    lo = [float('inf')] * 3
    hi = [-float('inf')] * 3
    start = None
    for t, p in reversed(w):
        lo = [min(a, b) for a, b in zip(lo, p)]
        hi = [max(a, b) for a, b in zip(hi, p)]
        if math.dist(lo, hi) > tol:
            break
        start = t
    return None if start is None else max(0.0, start - t_fault)


def peak_speed(ee, a, b, span=0.02, stamps=None):
    """Peak speed [m/s] over span; with stamps (t -> sample time) the arm's own sample times are used."""
    w = window(ee, a, b)
    if stamps:
        w = [(stamps[t], p) for t, p in w if stamps.get(t, 0.0) > 0.0]
    best, j = 0.0, 0
    for i in range(len(w)):
        while j < len(w) and w[j][0] - w[i][0] < span:
            j += 1
        if j < len(w):
            best = max(best, math.dist(w[j][1], w[i][1]) / (w[j][0] - w[i][0]))
    return best


def resume_time(sp, t_from, t_end, tol=0.0002):
    """First time after t_from the set-point moves more than tol from where it held."""
    w = window(sp, t_from, t_end)
    if not w:
        return None
    ref = w[0][1]
    for t, p in w:
        if math.dist(p, ref) > tol:
            return t
    return None


def right_affected(out, t_f, t_back, ee_r, sp_r, gaps):
    """[violation] when the right chain was affected by a fault of the left one: held, its set-point
    stream stalled (> 250 ms), or the arm not following what it was commanded; a still hand (e.g. the
    scripted surgeon pressing into the tissue) is not a fault."""
    held_r = [d for d in load(out, 'diag') if t_f <= float(d[0]) < t_back and
              d[2].startswith('teleop/right/velocity_integrator') and 'HOLD' in d[3]]
    path_r, cmd_r = (sum(math.dist(a[1], b[1]) for a, b in zip(window(x, t_f, t_back), window(x, t_f, t_back)[1:]))
                     for x in (ee_r, sp_r))
    gap = max(gaps) if gaps else float('inf')
    if held_r or gap > 0.25 or (cmd_r >= 0.001 and path_r < 0.25 * cmd_r):
        return ['right arm affected (%s, moved %.1f mm of %.1f mm commanded, longest set-point gap %.0f ms)'
                % ('held' if held_r else 'not held', 1e3 * path_r, 1e3 * cmd_r, 1e3 * gap)]
    return []


def judge(out, ev, nxt_t):
    """One fault event -> dict of measured values and the list of violated expectations."""
    name, t_f, t_back = ev['fault'], float(ev['t_fault']), float(ev['t_back'])
    side = 'left'
    ee, sp = poses(out, 'ee_' + side), poses(out, 'target_' + side, zero_stamp=False)
    ee_stamp = dict((float(x[0]), float(x[1])) for x in load(out, 'ee_' + side))
    ee_r, sp_r = poses(out, 'ee_right'), poses(out, 'target_right', zero_stamp=False)
    r = {'fault': name, 'expected': ev['expected']}
    keys = ev['checks'].split()
    bad = [x for x in ev.get('violations', '').split(';') if x]
    if keys == ['none']:
        r['verdict'] = 'ok' if not bad else 'VIOLATED: ' + '; '.join(bad)
        return r, bad
    if 'packets' in keys:
        return judge_packets(out, ev, r, bad, (sp, sp_r, ee, ee_stamp))
    # hold: the command chain (set-point frozen, re-anchors on the clutch aside) or the arm
    # the arm's hold in its own sample times: how long it moved, not how late its state arrived
    # (up to the arm's first silence of over 0.5 s: a restarted arm simulator starts elsewhere)
    ee_by_stamp = sorted((st, p) for (t, p), st in ((row, ee_stamp.get(row[0], 0.0)) for row in ee) if st > 0.0)
    run = window(ee_by_stamp, t_f, t_back)
    cut = next((i + 1 for i, (a, b) in enumerate(zip(run, run[1:])) if b[0] - a[0] > 0.5), len(run))
    # no sample of the arm after the fault: its controller died with it (nothing moves it any more)
    arm_hold = hold_time(run[:cut], t_f, t_back) if run else 0.0 if at(ee_by_stamp, t_f) else None
    hold = min([h for h in (hold_time(sp, t_f, t_back, tol=0.00005), arm_hold) if h is not None], default=None)
    r['hold [ms]'] = '-' if hold is None else '%.0f' % (1e3 * hold)
    # motion beyond the hold limit, in the arm's own sample times (not how late its states arrived)
    lim = float(ev['hold_limit'])
    ref = at(run[:cut], t_f + lim) or at(ee_by_stamp, t_f)
    moved = max((math.dist(p, ref[1]) for _, p in window(run[:cut], ref[0], t_back)), default=0.0) if ref else float('nan')
    r['arm motion after hold [mm]'] = '%.2f' % (1e3 * moved)
    t_res = resume_time(sp, t_back, nxt_t)
    if t_res is not None:
        before = at(ee, t_res)
        first = at(sp, t_res + 1e-6)
        jump = math.dist(first[1], before[1]) if before and first else float('nan')
        r['first set-point vs held [mm]'] = '%.2f' % (1e3 * jump)
        r['peak speed on recovery [mm/s]'] = '%.1f' % (1e3 * peak_speed(ee, t_res, t_res + 2.0, stamps=ee_stamp))
        r['resumed after [s]'] = '%.1f' % (t_res - t_f)
    else:
        r['first set-point vs held [mm]'] = r['peak speed on recovery [mm/s]'] = r['resumed after [s]'] = '-'
    gaps = [b[0] - a[0] for a, b in zip(window(sp_r, t_f, t_back), window(sp_r, t_f, t_back)[1:])]
    r['right arm: longest set-point gap [ms]'] = '%.0f' % (1e3 * max(gaps)) if gaps else 'none'
    # while the fault lasts: from 1 s after it to 0.1 s before the probe saw the arm back (the
    # collision node may get the returning arm's first pose a few ms before the probe does)
    coll = [float(c[1]) for c in load(out, 'collision') if t_f + 1.0 <= float(c[0]) < t_back - 0.1]
    r['collision distance left in fault'] = ('none' if not coll else 'NaN (unknown)' if all(math.isnan(c) for c in coll)
                                             else 'finite %d/%d' % (sum(not math.isnan(c) for c in coll), len(coll)))
    diags = sorted(set(d[2].split(':')[0] for d in load(out, 'diag') if t_f <= float(d[0]) < t_back + 2.0))
    r['/diagnostics ERROR/STALE'] = ', '.join(diags[:4]) + (' ...' if len(diags) > 4 else '') or 'none'
    # expectations (stated in run.sh before measuring)
    if 'hold' in keys and (hold is None or hold > lim):
        bad.append('hold %s ms > %.0f ms' % (r['hold [ms]'], 1e3 * lim))
    if 'hold' in keys and moved > 0.001:
        bad.append('moved %.2f mm during the fault' % (1e3 * moved))
    if 'resume' in keys:
        if t_res is None:
            bad.append('never resumed')
        elif jump > 0.001:
            bad.append('recovery jump %.2f mm > 1 mm' % (1e3 * jump))
        elif float(r['peak speed on recovery [mm/s]']) > 1e3 * SPEED_LIMIT:
            bad.append('recovery speed %s mm/s > 50' % r['peak speed on recovery [mm/s]'])
    if 'right' in keys:
        bad += right_affected(out, t_f, t_back, ee_r, sp_r, gaps)
    if 'diag' in keys and diags == []:
        bad.append('nothing reported on /diagnostics')
    if 'unknown' in keys and coll and not all(math.isnan(c) for c in coll):
        bad.append('collision distance stayed finite (stale green) while the pose was missing')
    if 'spoof' in keys:
        check_spoof(ee, sp, t_f, t_back, r, bad)
    if 'tanks' in keys:
        check_tanks(out, t_f, r, bad)
    if 'slow' in keys:
        check_slow(out, side, sp, ee, ee_stamp, t_f, t_back, r, bad)
    r['verdict'] = 'ok' if not bad else 'VIOLATED: ' + '; '.join(bad)
    return r, bad


def check_spoof(ee, sp, t_f, t_back, r, bad):
    """The arm never follows spoofed targets (2 cm deeper): it stays on the path of the real
    set-points of the last SPOOF_LAG s."""
    # path of the real set-points of the last SPOOF_LAG s (the arm follows them with its own lag)
    dev = max((min((math.dist(p, q) for _, q in window(sp, t - SPOOF_LAG, t + 1e-6)), default=0.0)
               for t, p in window(ee, t_f, t_back)), default=0.0)
    r['arm motion after hold [mm]'] = 'max %.2f from the real set-points' % (1e3 * dev)
    if dev > 0.004:
        bad.append('arm %.1f mm away from the real set-points' % (1e3 * dev))


def check_tanks(out, t_f, r, bad):
    """A restarted tank never has more energy than before the fault, and is not emptied."""
    notes = []
    for tank in ('master', 'slave'):
        e = [(float(x[0]), float(x[1])) for x in load(out, 'tank_' + tank)]
        before = at(e, t_f)
        gap = [b for a, b in zip(e, e[1:]) if t_f <= b[0] and b[0] - a[0] > 0.5]   # the first sample after the outage
        if not before or not gap:
            bad.append('tank_%s: no energy before the fault or no restart seen' % tank)
            continue
        notes.append('%s %.4f -> %.4f J' % (tank, before[1], gap[0][1]))
        # (the last published energy is up to one step older than the death: TANK_STEP_J may enter)
        if gap[0][1] > before[1] + TANK_STEP_J:
            bad.append('tank_%s came back with more energy (%.4f > %.4f J)' % (tank, gap[0][1], before[1]))
    r['resumed after [s]'] = '%s (tanks %s)' % (r['resumed after [s]'], ', '.join(notes))


def check_slow(out, side, sp, ee, ee_stamp, t_f, t_back, r, bad):
    """Degraded: set-point speed <= 20 % of 50 mm/s (+ margin) while the loss is reported; the arm's shown."""
    # (without the re-anchoring on each clutch press: the set-point then jumps to the measured pose)
    sp_stamp = dict((float(x[0]), float(x[1])) for x in load(out, 'target_' + side))
    clutch = [float(x[0]) for x in load(out, 'clutch')]
    moving = [(t, p) for t, p in sp if not any(c - 0.1 <= t <= c + 0.5 for c in clutch)]
    # while the integrator reported the loss (the respawned collision node ends it)
    lost = [float(d[0]) for d in load(out, 'diag') if t_f <= float(d[0]) < t_back and
            d[2].startswith('teleop/%s/velocity_integrator' % side) and 'collision monitoring lost' in d[3]]
    a, b = (min(lost), max(lost)) if lost else (t_f, t_f)
    v_sp = peak_speed(moving, a, b, span=0.1, stamps=sp_stamp)
    v = peak_speed(ee, a, b, span=0.1, stamps=ee_stamp)
    if not lost:
        bad.append('the loss of collision monitoring was not reported by the left velocity_integrator')
    r['peak speed on recovery [mm/s]'] = 'set-point %.1f, arm %.1f (degraded %.1f s)' % (1e3 * v_sp, 1e3 * v, b - a)
    if v_sp > 0.012:
        bad.append('set-point at %.1f mm/s without collision monitoring' % (1e3 * v_sp))


def link_at(rows, t, after=False):
    """The receiver's counters (t, received, rejected, {reason: n}) last before t (first after t)."""
    rows = [x for x in rows if (float(x[0]) >= t if after else float(x[0]) <= t) and x[2] and x[3]]
    if not rows:
        return None
    x = rows[0] if after else rows[-1]
    return float(x[0]), int(x[2]), int(x[3]), dict((k, int(n)) for k, n in (c.split('=') for c in x[4:]))


def judge_packets(out, ev, r, bad, rec):
    """Hostile console datagrams: counted as rejected, the real stream keeps its rate (no console-link
    STALE with a set-point gap over hold_limit), the arm never faster than the 50 mm/s limit, the
    receiver survives (run.sh's violations). Holds for other reasons are shown, not judged here."""
    t_f, t_back, lim = float(ev['t_fault']), float(ev['t_back']), float(ev['hold_limit'])
    sp, sp_r, ee, ee_stamp = rec
    r.update((c, '-') for c in COLUMNS[2:-1])
    sent = dict((x[0], int(x[1])) for x in load(out, 'sent') if x[1].isdigit()).get(ev['fault'], 0)
    link = load(out, 'link')
    a, b, pre = link_at(link, t_f - 0.05), link_at(link, t_back + 1.2, after=True), link_at(link, t_f - 6.0)
    if not (a and b and pre):
        bad.append('no console-link counters on /diagnostics')
        r['verdict'] = 'VIOLATED: ' + '; '.join(bad)
        return r, bad
    rejected = b[2] - a[2]
    reasons = ', '.join('%s +%d' % (k, n - a[3].get(k, 0)) for k, n in sorted(b[3].items()) if n > a[3].get(k, 0))
    nominal = (a[1] - pre[1]) / (a[0] - pre[0])
    during = (b[1] - a[1]) / (b[0] - a[0])
    r['/diagnostics ERROR/STALE'] = 'rejected +%d of %d sent (%s)' % (rejected, sent, reasons)
    r['arm motion after hold [mm]'] = 'real stream %.0f Hz (before %.0f Hz)' % (during, nominal)
    gaps = {}
    for side, rows in (('left', sp), ('right', sp_r)):
        w = window(rows, t_f, t_back)
        gaps[side] = max([y[0] - x[0] for x, y in zip(w, w[1:])], default=float('inf'))
    r['hold [ms]'] = 'longest set-point gap %.0f / %.0f' % (1e3 * gaps['left'], 1e3 * gaps['right'])
    v = peak_speed(ee, t_f, t_back + 1.0, stamps=ee_stamp)
    r['peak speed on recovery [mm/s]'] = 'arm %.1f' % (1e3 * v)
    if rejected < 0.9 * sent * ('flood' not in ev['fault']) or rejected <= 0:
        bad.append('only %d of %d hostile datagrams counted as rejected' % (rejected, sent))
    if during < 0.9 * nominal:
        bad.append('real stream %.0f Hz < 90 %% of %.0f Hz' % (during, nominal))
    holds = dict((d[2].split(':')[0].split('/')[1] if 'velocity_integrator' in d[2] else d[2].split(':')[0],
                  d[3].split(';')[0]) for d in load(out, 'diag') if t_f <= float(d[0]) < t_back + 0.5
                 and ('console link' in d[2] or 'HOLD' in d[3]))
    if holds:
        r['resumed after [s]'] = 'held: ' + ', '.join('%s (%s)' % kv for kv in sorted(holds.items()))
    link_lost = [k for k, m in holds.items() if 'console link' in k or 'console link' in m]
    if link_lost and max(gaps.values()) > lim:
        bad.append('the real stream was interrupted (%s), set-point gap %.0f ms > %.0f ms'
                   % (', '.join(link_lost), 1e3 * max(gaps.values()), 1e3 * lim))
    if v > SPEED_LIMIT:
        bad.append('arm at %.1f mm/s > 50 mm/s' % (1e3 * v))
    r['verdict'] = 'ok' if not bad else 'VIOLATED: ' + '; '.join(bad)
    return r, bad



COLUMNS = ['fault', 'expected', 'hold [ms]', 'arm motion after hold [mm]', 'resumed after [s]',
           'first set-point vs held [mm]', 'peak speed on recovery [mm/s]', 'right arm: longest set-point gap [ms]',
           'collision distance left in fault', '/diagnostics ERROR/STALE', 'verdict']


def analyse(out):
    with open(os.path.join(out, 'events.csv')) as f:
        events = list(csv.DictReader(f))
    rows, violated = [], 0
    notes = dict((x[0], x[1]) for x in load(out, 'notes'))
    for i, ev in enumerate(events):
        nxt = float(events[i + 1]['t_fault']) if i + 1 < len(events) else float('inf')
        r, bad = judge(out, ev, nxt)
        if notes.get(ev['fault']):
            r['verdict'] += ': ' + notes[ev['fault']]
        rows.append(r)
        violated += bool(bad)
    lines = ['| ' + ' | '.join(COLUMNS) + ' |', '|' + '---|' * len(COLUMNS)]
    lines += ['| ' + ' | '.join(str(r.get(c, '')) for c in COLUMNS) + ' |' for r in rows]
    text = '\n'.join(lines) + '\n\n%d of %d faults met every expectation.\n' % (len(rows) - violated, len(rows))
    with open(os.path.join(out, 'faults.md'), 'w') as f:
        f.write(text)
    sys.stdout.write(text)
    return 1 if violated else 0


def main(argv):
    cmd = argv[1] if len(argv) > 1 else ''
    if cmd == 'probe':
        probe(argv[2])
    elif cmd == 'pid':
        node_pid(argv[2])
    elif cmd == 'wait-link-restart':
        return wait_link_restart(argv[2], float(argv[3]), float(argv[4]))
    elif cmd in ('spoof-force', 'spoof-target'):
        spoof(cmd[6:], argv[2], float(argv[3]))
    elif cmd == 'analyse':
        return analyse(argv[2])
    else:
        sys.stderr.write(__doc__)
        return 2
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv))
