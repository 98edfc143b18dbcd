"""Energy at the teleoperation's power ports from a recording, independent of the tanks' self-report.

Master port (per side): the wrench the tank lets through to the device (``/teleop/<s>/tank_wrench``)
times the measured device twist (``/teleop/<s>/master_twist``): positive power is energy delivered
to the operator. Slave port: the twist the tank lets through to the robot
(``/teleop/<s>/tank_twist``) times the force of the tool on the tissue
(``contact_force_sign * /mesa_<s>/contact_force``): positive power is energy delivered by the robot.
Each product is integrated over the action's own stamps with the latest conjugate sample (zero-order
hold), the way the tank pairs them.

``energy_balance`` gives, over time, the energy delivered (integral of the positive power), the
energy injected at the ports (integral of the negative power: the operator pushing the device,
the tissue pushing the tool) and their difference, the net energy out of the teleoperator. Energy
that entered = initial tank energy (first ``/teleop/tank_*/energy`` samples; 0 when the tanks are
bypassed, as nothing is stored) + energy injected. Passivity holds when the net energy out never
exceeds the initial tank energy: delivered <= entered at every instant.
"""
import bisect
import math


def dot6(a, b):
    return sum(x * y for x, y in zip(a, b))


def port_power(actions, conjugates):
    """[(t, power W, dt s)] for action samples [(t, 6-vector)] against conjugate samples
    [(t, 6-vector)] (zero-order hold of the latest conjugate not newer than the action; actions
    before the first conjugate have zero power). dt is the interval to the next action (the last
    one gets the median interval)."""
    if not actions:
        return []
    ct = [c[0] for c in conjugates]
    out = []
    for i, (t, a) in enumerate(actions):
        k = bisect.bisect_right(ct, t) - 1
        p = dot6(a, conjugates[k][1]) if k >= 0 else 0.0
        out.append([t, p, 0.0])
    dts = [actions[i + 1][0] - actions[i][0] for i in range(len(actions) - 1)]
    for i, dt in enumerate(dts):
        out[i][2] = max(0.0, dt)
    if dts:
        out[-1][2] = sorted(dts)[len(dts) // 2]
    return [tuple(r) for r in out]


def port_energy(power):
    """(delivered, injected) [J] of one port's [(t, P, dt)]: integrals of its positive and negative power."""
    d = sum(p * dt for _, p, dt in power if p > 0.0)
    return d, -sum(p * dt for _, p, dt in power if p < 0.0)


def contact_summary(forces, threshold=0.1):
    """(max |F| [N], seconds with |F| > threshold [N]) of [(t, 3+-vector)] force samples (ZOH)."""
    mags = [(t, math.sqrt(sum(v * v for v in f[:3]))) for t, f in forces]
    peak = max((m for _, m in mags), default=0.0)
    held = sum(b[0] - a[0] for a, b in zip(mags, mags[1:]) if a[1] > threshold)
    return peak, held


def travel(positions):
    """Largest distance [m] of [(t, (x, y, z))] from its first position (0 without samples)."""
    if not positions:
        return 0.0
    p0 = positions[0][1]
    return max(math.sqrt(sum((a - b) ** 2 for a, b in zip(p, p0))) for _, p in positions)


def energy_balance(powers, e0):
    """powers: list of [(t, P, dt)] (one per port); e0: initial stored energy [J].

    Returns dict: t, delivered, injected, net (lists over the merged time axis) and the summary
    delivered_J, injected_J, entered_J (= e0 + injected), net_max_J, passive (net <= e0 at every
    instant, with 1 mJ + 0.5 % numerical tolerance), margin_J (e0 - net_max).
    """
    events = sorted((t, p * dt) for port in powers for (t, p, dt) in port)
    ts, delivered, injected, net = [], [], [], []
    d = i = 0.0
    net_max = 0.0
    for t, e in events:
        if e > 0:
            d += e
        else:
            i -= e
        ts.append(t)
        delivered.append(d)
        injected.append(i)
        net.append(d - i)
        net_max = max(net_max, d - i)
    tol = 1e-3 + 5e-3 * max(e0, d)
    return {'t': ts, 'delivered': delivered, 'injected': injected, 'net': net,
            'delivered_J': d, 'injected_J': i, 'entered_J': e0 + i, 'net_max_J': net_max,
            'passive': net_max <= e0 + tol, 'margin_J': e0 - net_max}


def engaged_windows(states, t_end):
    """[(t0, t1)] where the operator drives the slave: none of the flags set (clutch, stale, hold).

    states: [(t, (flag, ...))] in time order; the last window is closed at t_end."""
    out, start = [], None
    for t, flags in states:
        engaged = not any(flags)
        if engaged and start is None:
            start = t
        elif not engaged and start is not None:
            out.append((start, t))
            start = None
    if start is not None and t_end > start:
        out.append((start, t_end))
    return out


def device_windows(states, holds, t_end):
    """engaged_windows from the recorded device states [(t, (clutch, stale))] and the latched hold
    [(t, bool)] (either may start later: until its first sample a flag counts as clear)."""
    events = sorted([(t, 0, tuple(v)) for t, v in states] + [(t, 1, (bool(v),)) for t, v in holds])
    if not events:
        return []
    flags = [(False, False), (False,)]
    timeline = [(events[0][0], (False, False, False))]
    for t, k, v in events:
        if flags[k] != v:
            flags[k] = v
            timeline.append((t, flags[0] + flags[1]))
    return engaged_windows(timeline, t_end)


def tracking_error(master, slave, scale, windows=None):
    """RMS and max [m] of |scale * (master - master0) - (slave - slave0)| at the slave samples.

    master, slave: [(t, (x, y, z))]; the master position is held (latest not newer). Without
    windows, master0/slave0 are the first samples. With windows [(t0, t1)] (the operator engaged,
    :func:`engaged_windows`), only slave samples inside a window count and each window re-anchors
    both at its first samples: a clutch re-indexes the master against the slave, as the
    teleoperation does."""
    if not master or not slave:
        return float('nan'), float('nan')
    if windows is None:
        windows = [(min(master[0][0], slave[0][0]), max(master[-1][0], slave[-1][0]) + 1.0)]
    mt = [m[0] for m in master]
    st = [x[0] for x in slave]
    errs = []
    for t0, t1 in windows:
        anchor = None
        for t, s in slave[bisect.bisect_left(st, t0):]:
            if t >= t1:
                break
            k = bisect.bisect_right(mt, t) - 1
            if k < 0 or mt[k] < t0:
                continue
            m = master[k][1]
            if anchor is None:
                anchor = (m, s)
            m0, s0 = anchor
            e = [scale * (m[j] - m0[j]) - (s[j] - s0[j]) for j in range(3)]
            errs.append(math.sqrt(sum(v * v for v in e)))
    if not errs:
        return float('nan'), float('nan')
    return math.sqrt(sum(e * e for e in errs) / len(errs)), max(errs)


def time_to_hold(setpoints, t_cut, tolerance=1e-5, still_for=0.5):
    """Seconds from t_cut until the set-point stays within ``tolerance`` [m] of one position for at
    least ``still_for`` s and until the end (None when it never holds). setpoints: [(t, (x, y, z))]."""
    after = [(t, p) for t, p in setpoints if t >= t_cut]
    if len(after) < 2 or after[-1][0] - after[0][0] < still_for:
        return None
    last = after[-1][1]
    k = len(after) - 1
    while k > 0 and max(abs(a - b) for a, b in zip(after[k - 1][1], last)) <= tolerance:
        k -= 1
    if after[-1][0] - after[k][0] < still_for:
        return None
    return max(0.0, after[k][0] - t_cut)
