"""Demo report: plots and an index.html from a platform recording.

``build_report(bag_path, out_dir, check_results, extras)`` reads the recording (the main bag
``bag_path`` and its part bags, ``recording.recording_bags``) and writes PNG plots and ``index.html``:
master vs slave trajectory per channel, the instrument jaw following the Simball clip, tool
distances with the thresholds, tank energies, contact forces, estimated vs true contact depths, one
recorded endoscope frame with the contact estimate drawn (saras_bringup.contact_frame), the augmented
endoscope frame and rviz screenshot (files produced live by the demo and passed in ``extras``), and
the table of recorded topics. A plot whose topics are absent from the bag is listed as "not recorded"
instead of silently disappearing.
"""
import html
import json
import os

import numpy as np

import matplotlib
matplotlib.use('Agg')
import matplotlib.pyplot as plt  # noqa: E402

from saras_bringup.contact_frame import PATCH_RADIUS, write_contact_frame  # noqa: E402
from saras_bringup.recording import open_bags, read_merged, recording_bags, start_time  # noqa: E402

SIDES = ('left', 'right')
TOOLS = ('mesa_left', 'mesa_right', 'PSM1', 'PSM2')


def read_series(bags, topics):
    """{topic: list of (t_bag [s], msg)} for the given topics (deserialized) from one open bag or a
    list (a recording's bags: receive-time order across them)."""
    out = {t: [] for t in topics}
    for topic, msg, t in read_merged(bags if isinstance(bags, (list, tuple)) else [bags], topics=list(topics)):
        out[topic].append((t.to_sec(), msg))
    return out


def _positions(series):
    if not series:
        return np.zeros(0), np.zeros((0, 3))
    t = np.array([s[0] for s in series])
    p = np.array([[m.pose.position.x, m.pose.position.y, m.pose.position.z] for _, m in series])
    return t, p


def _scalar(series, index=None):
    if not series:
        return np.zeros(0), np.zeros(0)
    t = np.array([s[0] for s in series])
    if index is None:
        v = np.array([float(m.data) for _, m in series])
    else:
        v = np.array([m.data[index] if len(m.data) > index else np.nan for _, m in series])
    return t, v


class Report(object):
    def __init__(self, out_dir, t0):
        self.out_dir = out_dir
        self.t0 = t0
        self.sections = []   # (title, html)

    def figure(self, name, title, draw, caption=''):
        fig = draw()
        if fig is None:
            self.sections.append((title, '<p class="missing">not recorded: %s</p>' % html.escape(caption)))
            return None
        path = os.path.join(self.out_dir, name)
        fig.savefig(path, dpi=90, bbox_inches='tight')
        plt.close(fig)
        self.sections.append((title, '<img src="%s" alt="%s"/><p>%s</p>' % (
            name, html.escape(title), html.escape(caption))))
        return path


def plot_trajectories(data, side, scale, t0):
    tm, pm = _positions(data.get('/teleop/%s/master_pose' % side, []))
    ts, ps = _positions(data.get('/mesa_%s/ee_pose' % side, []))
    tt, pt = _positions(data.get('/mesa_%s/target_pose' % side, []))
    if len(ts) == 0 or len(tm) == 0:
        return None
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    for k, ax in enumerate(axes):
        ax.plot(tm - t0, 1e3 * scale * (pm[:, k] - pm[0, k]), label='master x scale (%.2f)' % scale, lw=1)
        if len(tt):
            ax.plot(tt - t0, 1e3 * (pt[:, k] - ps[0, k]), '--', label='slave set-point', lw=1)
        ax.plot(ts - t0, 1e3 * (ps[:, k] - ps[0, k]), label='slave measured', lw=1)
        ax.set_ylabel('%s [mm]' % 'xyz'[k])
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc='upper right', fontsize=8)
    axes[0].set_title('%s channel: displacement from start in mesa_%s/sbs_world' % (side, side))
    axes[-1].set_xlabel('time [s]')
    return fig


PEDAL_TOPICS = {'clutch': '/dvrk/footpedals/clutch', 'camera': '/dvrk/footpedals/camera',
                'coag': '/dvrk/footpedals/coag', 'head sensor': '/dvrk/footpedals/operatorpresent'}


def pedal_intervals(series, t_end):
    """[(t_press, t_release)] from sensor_msgs/Joy events (buttons[0] 1 = pressed)."""
    out, start = [], None
    for t, m in series:
        pressed = bool(m.buttons and m.buttons[0])
        if pressed and start is None:
            start = t
        elif not pressed and start is not None:
            out.append((start, t))
            start = None
    if start is not None:
        out.append((start, t_end))
    return out


def plot_console(data, t0, scale=0.2):
    """da Vinci console: MTMR (scaled) vs PSM1 displacement with the foot-pedal events as spans."""
    tm, pm = _positions(data.get('/dvrk/MTMR/position_cartesian_current', []))
    ts, ps = _positions(data.get('/dvrk/PSM1/position_cartesian_current', []))
    if len(tm) == 0 or len(ts) == 0:
        return None
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    colours = {'clutch': 'tab:red', 'camera': 'tab:blue', 'coag': 'tab:orange', 'head sensor': 'tab:green'}
    t_end = max(tm[-1], ts[-1])
    for k, ax in enumerate(axes):
        ax.plot(tm - t0, 1e3 * scale * (pm[:, k] - pm[0, k]), label='MTMR x %.2f' % scale, lw=1)
        ax.plot(ts - t0, 1e3 * (ps[:, k] - ps[0, k]), label='PSM1', lw=1)
        for name, topic in PEDAL_TOPICS.items():
            for i, (a, b) in enumerate(pedal_intervals(data.get(topic, []), t_end)):
                ax.axvspan(a - t0, b - t0, color=colours[name], alpha=0.08 if name == 'head sensor' else 0.25,
                           label=name + ' pressed' if (k == 0 and i == 0) else None)
        ax.set_ylabel('%s [mm]' % 'xyz'[k])
        ax.grid(True, alpha=0.3)
    axes[0].legend(loc='upper right', fontsize=8)
    axes[0].set_title('da Vinci console: MTMR (scaled) vs PSM1, displacement from start in each base')
    axes[-1].set_xlabel('time [s]')
    return fig


def plot_distances(data, thresholds, t0):
    series = data.get('/collision/distances', [])
    if not series:
        return None
    fig, ax = plt.subplots(figsize=(9, 4))
    for i, name in enumerate(TOOLS):
        t, v = _scalar(series, i)
        ax.plot(t - t0, 1e3 * v, label=name, lw=1)
    colours = {'collision': 'red', 'warning': 'orange'}
    for key, value in thresholds.items():
        ax.axhline(1e3 * value, color=colours.get(key, 'gray'), ls='--', lw=1,
                   label='%s threshold %.0f mm' % (key, 1e3 * value))
    ax.set_ylabel('minimum distance [mm]')
    ax.set_xlabel('time [s]')
    ax.set_ylim(bottom=min(-5.0, ax.get_ylim()[0]), top=min(ax.get_ylim()[1], 150.0))
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8, ncol=3)
    ax.set_title('/collision/distances (tool-tool and tool-bone)')
    return fig


def colour_occupancy(series, thresholds):
    """Per tool, how many /collision/distances samples fall in each colour of the visual feedback.

    The VisualFeedback nodelet draws a tool red at distance <= collision threshold, yellow at
    <= warning threshold and green above (D7.2 Section 7). Returns ``{tool: {'red': n, 'yellow': n,
    'green': n}}`` over the ``TOOLS`` entries present in the samples (NaN = unknown, not counted).
    """
    red, warn = thresholds['collision'], thresholds['warning']
    out = {}
    for i, name in enumerate(TOOLS):
        _, v = _scalar(series, i)
        v = v[np.isfinite(v)]
        if not len(v):
            continue
        n_red = int(np.count_nonzero(v <= red))
        n_yellow = int(np.count_nonzero((v > red) & (v <= warn)))
        out[name] = {'red': n_red, 'yellow': n_yellow, 'green': int(len(v)) - n_red - n_yellow}
    return out


def occupancy_html(occ):
    """HTML table of :func:`colour_occupancy` plus the colours that occurred over the run."""
    rows = ''.join('<tr><td>%s</td><td>%d</td><td>%d</td><td>%d</td></tr>'
                   % (html.escape(tool), c['red'], c['yellow'], c['green']) for tool, c in occ.items())
    seen = [c for c in ('red', 'yellow', 'green') if any(o[c] for o in occ.values())]
    missing = [c for c in ('red', 'yellow', 'green') if c not in seen]
    verdict = ('all three colours occurred' if not missing else
               '<span class="missing">never shown: %s</span>' % ', '.join(missing))
    return ('<table><tr><th>tool</th><th>red samples</th><th>yellow samples</th><th>green samples</th></tr>'
            '%s</table><p>Over the run: %s.</p>' % (rows, verdict))


def plot_energies(data, t0, limits):
    names = ('/teleop/tank_master/energy', '/teleop/tank_slave/energy')
    if not any(data.get(n) for n in names):
        return None
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for n in names:
        t, v = _scalar(data.get(n, []))
        if len(t):
            ax.plot(t - t0, v, label=n.split('/')[2], lw=1)
    for key, value in limits.items():
        ax.axhline(value, color='gray', ls=':', lw=1)
        ax.text(ax.get_xlim()[0], value, ' ' + key, fontsize=7, va='bottom', color='gray')
    ax.set_ylabel('tank energy T [J]')
    ax.set_xlabel('time [s]')
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title('Energy tanks (passivity layer)')
    return fig


def plot_forces(data, t0):
    names = ['/mesa_%s/contact_force' % s for s in SIDES]
    if not any(data.get(n) for n in names):
        return None
    fig, ax = plt.subplots(figsize=(9, 3.5))
    for n in names:
        series = data.get(n, [])
        if series:
            t = np.array([s[0] for s in series])
            f = np.array([np.linalg.norm([m.linear.x, m.linear.y, m.linear.z]) for _, m in series])
            ax.plot(t - t0, f, label=n, lw=1)
    ax.set_ylabel('|contact force| [N]')
    ax.set_xlabel('time [s]')
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=8)
    ax.set_title('Vision-based contact forces (D7.2 Section 8)')
    return fig


def _jaw(series, joint):
    """(t, jaw [rad]) of ``joint`` in a JointState series."""
    pts = [(t, m.position[m.name.index(joint)]) for t, m in series
           if joint in m.name and m.name.index(joint) < len(m.position)]
    return np.array([p[0] for p in pts]), np.array([p[1] for p in pts])


def plot_jaw(data, t0):
    """Simball clip angle, commanded jaw (jaw_target) and measured jaw (joint_states) per arm."""
    if not any(data.get('/mesa_%s/jaw_target' % s) or data.get('/mesa_%s/joint_states' % s) for s in SIDES):
        return None
    fig, axes = plt.subplots(1, 2, figsize=(11, 3.2), sharey=True)
    for ax, side in zip(axes, SIDES):
        clip = data.get('/touchball/%s/state' % side, [])
        if clip:
            ax.plot(np.array([c[0] for c in clip]) - t0, [m.clip_angle for _, m in clip],
                    color='gray', lw=0.8, label='Simball clip angle')
        for topic, label, style in (('/mesa_%s/jaw_target' % side, 'commanded (jaw_target)', '--'),
                                    ('/mesa_%s/joint_states' % side, 'measured (joint_states)', '-')):
            t, v = _jaw(data.get(topic, []), 'mesa_%s/jaw' % side)
            if len(t):
                ax.plot(t - t0, v, style, lw=1.2, label=label)
        ax.set_title('mesa_%s' % side)
        ax.set_xlabel('time [s]')
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7)
    axes[0].set_ylabel('angle [rad]')
    fig.suptitle('Instrument jaw following the Simball clip')
    return fig


def plot_contact_depths(data, t0):
    """Estimated (ContactEstimator, /mesa_<s>/contact_estimate) vs true (contact_sim) depth per tool."""
    if not any(data.get('/mesa_%s/contact_truth' % s) or data.get('/mesa_%s/contact_estimate' % s) for s in SIDES):
        return None
    fig, axes = plt.subplots(len(SIDES), 1, figsize=(9, 5), sharex=True)
    for ax, side in zip(axes, SIDES):   # at the image and pose stamps (truth_series), as contact_agreement
        tt, td = truth_series(data, side)
        if tt.size:
            ax.plot(tt - t0, 1e3 * td, 'k-', lw=1.2, label='true (contact_sim)')
        est = data.get('/mesa_%s/contact_estimate' % side, [])
        known = [(m.data[0], m.data[2]) for t, m in est if len(m.data) > 2 and m.data[1] > 0.5]
        unknown = [m.data[0] for t, m in est if len(m.data) > 2 and m.data[1] <= 0.5]
        if known:
            ax.plot([t - t0 for t, _ in known], [1e3 * d for _, d in known], '.', ms=3, color='tab:blue',
                    label='estimated (stereo)')
        if unknown:
            ax.plot([t - t0 for t in unknown], [0.0] * len(unknown), '|', ms=6, color='tab:gray',
                    label='estimate unknown')
        ax.set_ylabel('%s depth [mm]' % side)
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=7, loc='upper right')
    axes[0].set_title('Contact depth: vision estimate vs ground truth (D7.2 Section 8)')
    axes[-1].set_xlabel('time [s]')
    return fig


def plot_tip_heights(data, t0):
    """Signed distance of each tool tip to the simulated tissue (contact_sim's truth): working height,
    dips, contacts below 0."""
    series = dict((s, [(t - t0, 1e3 * m.data[3]) for t, m in data.get('/mesa_%s/contact_truth_tip' % s, [])
                       if len(m.data) > 3]) for s in SIDES)
    if not any(series.values()):
        return None
    fig, ax = plt.subplots(figsize=(9, 3))
    for side, rows in sorted(series.items()):
        if rows:
            ax.plot([t for t, _ in rows], [d for _, d in rows], lw=1.0, label=side)
    ax.axhline(0.0, color='k', lw=0.8)
    ax.set_ylabel('tip above tissue [mm]')
    ax.set_xlabel('time [s]')
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7, loc='upper right')
    return fig


def truth_series(data, side):
    """(times, depths) of the contact truth: contact_sim's tip truth at the stamps of the poses it was
    computed from (depth = max(0, -signed distance)); bags without those stamps: /contact_truth at its
    recording time (late by the transport, so the comparison then carries that lag)."""
    tip = [m.data for _, m in data.get('/mesa_%s/contact_truth_tip' % side, []) if len(m.data) > 4]
    if tip:
        tip.sort(key=lambda d: d[4])
        return np.array([d[4] for d in tip]), np.array([max(0.0, -d[3]) for d in tip])
    truth = data.get('/mesa_%s/contact_truth' % side, [])
    return np.array([t for t, _ in truth]), np.array([m.depth for _, m in truth])


def contact_agreement(data, max_age=0.1):
    """Per side: estimates, unknown share, contact frames of the truth, the depth error of the known
    estimates against the truth at their image stamp (interpolated between the truth samples around it,
    the nearer within ``max_age`` s; :func:`truth_series`), over all of them and over those in true
    contact, and the latency from the image stamp to the estimate's recording."""
    rows = {}
    for side in SIDES:
        tt, td = truth_series(data, side)
        timed = [(t, m.data) for t, m in data.get('/mesa_%s/contact_estimate' % side, []) if len(m.data) > 4]
        est = [d for _, d in timed]
        if not tt.size or not est:
            continue
        err, err_contact, known_in_contact, in_contact = [], [], 0, 0
        for d in est:
            i = int(np.clip(np.searchsorted(tt, d[0]), 1, len(tt) - 1))
            i = i - 1 if abs(tt[i - 1] - d[0]) < abs(tt[i] - d[0]) else i
            if abs(tt[i] - d[0]) > max_age:
                continue
            true = float(np.interp(d[0], tt, td))
            in_contact += true > 0
            if d[1] > 0.5:
                err.append(d[2] - true)
                known_in_contact += true > 0
                if true > 0:
                    err_contact.append(d[2] - true)
        e = np.abs(np.array(err))
        ec = np.abs(np.array(err_contact))
        lat = np.array([t - d[0] for t, d in timed])
        rows[side] = {'estimates': len(est), 'unknown': sum(d[1] <= 0.5 for d in est) / float(len(est)),
                      'truth_contact': int(in_contact), 'known_in_contact': int(known_in_contact),
                      'rms_mm': 1e3 * float(np.sqrt(np.mean(e ** 2))) if e.size else float('nan'),
                      'p95_mm': 1e3 * float(np.percentile(e, 95)) if e.size else float('nan'),
                      'max_true_mm': 1e3 * float(td.max()),
                      'rms_contact_mm': 1e3 * float(np.sqrt(np.mean(ec ** 2))) if ec.size else float('nan'),
                      'latency_ms': tuple(1e3 * float(np.percentile(lat, q)) for q in (50, 95))}
    return rows


def contact_agreement_html(rows):
    if not rows:
        return '<p class="missing">no contact truth and estimate recorded</p>'
    out = ['<tr><th>tool</th><th>estimates</th><th>unknown</th><th>deepest true contact [mm]</th>'
           '<th>frames in true contact (known)</th><th>depth error RMS / p95 [mm]</th>'
           '<th>depth error RMS in contact [mm]</th><th>latency p50 / p95 [ms]</th></tr>']
    for side, r in sorted(rows.items()):
        out.append('<tr><td>%s</td><td>%d</td><td>%.0f %%</td><td>%.1f</td><td>%d (%d)</td><td>%.2f / %.2f</td>'
                   '<td>%.2f</td><td>%.0f / %.0f</td></tr>'
                   % (side, r['estimates'], 100 * r['unknown'], r['max_true_mm'], r['truth_contact'],
                      r['known_in_contact'], r['rms_mm'], r['p95_mm'], r['rms_contact_mm'],
                      r['latency_ms'][0], r['latency_ms'][1]))
    return ('<table>%s</table><p>known estimates vs the truth recorded nearest their image stamp; in contact: '
            'where the truth is in contact; latency: image stamp to the estimate\'s recording</p>' % ''.join(out))


def contact_frame_section(rep, bag_path, out_dir, patch_radius):
    """One recorded endoscope frame with the contact estimates drawn (saras_bringup.contact_frame)."""
    title = 'Vision contact estimate on the endoscope image'
    try:
        caption = write_contact_frame(bag_path, os.path.join(out_dir, 'contact_frame.png'), SIDES, patch_radius)
    except Exception as e:  # a broken drawing must not cost the rest of the report
        caption, why = None, 'drawing failed: %s' % e
    else:
        why = 'no contact estimate with a surface, or its left image / camera_info not recorded'
    if caption is None:
        rep.sections.append((title, '<p class="missing">%s</p>' % html.escape(why)))
    else:
        rep.sections.append((title, '<img src="contact_frame.png" alt="%s"/><p>%s</p>' % (
            html.escape(title), html.escape(caption))))


def find_param(params, key):
    """First value of ``key`` anywhere in a nested rosparam dump (or None)."""
    if isinstance(params, dict):
        if key in params and isinstance(params[key], (int, float)):
            return params[key]
        for v in params.values():
            found = find_param(v, key)
            if found is not None:
                return found
    return None


def topic_table_html(results):
    rows = ['<tr><th>topic</th><th>group</th><th>type</th><th>messages</th><th>rate [Hz]</th>'
            '<th>nominal [Hz]</th><th>seq gaps</th><th>stamp gaps</th><th>status</th></tr>']
    for r in results:
        status = 'ok' if r['ok'] else (r.get('problem') or 'missing')
        cls = 'ok' if r['ok'] else ('bad' if r['required'] else 'warn')
        rows.append('<tr class="%s"><td>%s</td><td>%s</td><td>%s</td><td>%d</td><td>%.1f</td>'
                    '<td>%s</td><td>%d</td><td>%d</td><td>%s</td></tr>' % (
                        cls, html.escape(r['topic']), html.escape(r['group']),
                        html.escape(r.get('type', '')), r['count'], r['rate'],
                        ('%.0f' % r['nominal_rate']) if r['nominal_rate'] > 0 else '-',
                        r['seq_gaps'], r['stamp_gaps'], html.escape(status)))
    return '<table>%s</table>' % '\n'.join(rows)


CSS = """body{font-family:sans-serif;margin:2em;max-width:1100px}img{max-width:100%;border:1px solid #ccc}
table{border-collapse:collapse;font-size:12px}td,th{border:1px solid #ccc;padding:2px 6px}
tr.bad{background:#fdd}tr.warn{background:#ffd}.missing{color:#a00}h2{margin-top:1.5em}"""


def contact_sections(rep, data, t0, bag_path, out_dir, params):
    """D7.2 Section 8 in the report: forces, estimated vs true depth (plot, table, contact.json), tip
    heights and one endoscope frame with the estimate drawn."""
    rep.figure('contact_forces.png', 'Contact forces', lambda: plot_forces(data, t0),
               '/mesa_left/contact_force, /mesa_right/contact_force')
    rep.figure('contact_depths.png', 'Contact depth: estimated vs true', lambda: plot_contact_depths(data, t0),
               '/mesa_<side>/contact_estimate (stereo ContactEstimator; grey ticks: unknown) and '
               '/mesa_<side>/contact_truth (contact_sim, the simulated tissue)')
    agreement = contact_agreement(data)
    rep.sections.append(('Contact depth: estimate vs truth', contact_agreement_html(agreement)))
    with open(os.path.join(out_dir, 'contact.json'), 'w') as stream:     # for tests and scripts
        json.dump(agreement, stream, indent=1)
    rep.figure('tip_heights.png', 'Tool tips above the tissue', lambda: plot_tip_heights(data, t0),
               '/mesa_<side>/contact_truth_tip (contact_sim): signed distance of the tip to the simulated tissue; '
               'below 0 = in contact')
    contact_frame_section(rep, bag_path, out_dir, float(find_param(params, 'patch_radius') or PATCH_RADIUS))


def build_report(bag_path, out_dir, check, params=None, extras=None, thresholds=None, summary='',
                 sections=()):
    """Write the plots and index.html into ``out_dir``; returns the index path.

    check: dict with 'results' and 'problems' (from bag_check --json); params: rosparam dump (dict);
    extras: list of (title, path relative to out_dir, caption): PNG captures are shown as images,
    .txt files (e.g. a benchmark table) as preformatted text; sections: (title, HTML) blocks shown
    first (e.g. one per machine of a cluster run).
    """
    os.makedirs(out_dir, exist_ok=True)
    params = params or {}
    thresholds = thresholds or {
        'collision': float(find_param(params, 'collision_threshold') or 0.005),
        'warning': float(find_param(params, 'warning_threshold') or 0.02)}
    scale = float(find_param(params, 'scale_factor') or 1.0)
    limits = {}
    for key in ('T_max', 'T_ava', 'T_req', 'T_min'):
        v = find_param(params, key)
        if v is not None:
            limits[key] = float(v)
    topics = ['/teleop/%s/master_pose' % s for s in SIDES] + ['/mesa_%s/ee_pose' % s for s in SIDES]
    topics += ['/mesa_%s/target_pose' % s for s in SIDES] + ['/mesa_%s/contact_force' % s for s in SIDES]
    topics += ['/mesa_%s/contact_truth' % s for s in SIDES] + ['/mesa_%s/contact_estimate' % s for s in SIDES]
    topics += ['/mesa_%s/contact_truth_tip' % s for s in SIDES]
    topics += ['/collision/distances', '/teleop/tank_master/energy', '/teleop/tank_slave/energy']
    topics += ['/dvrk/MTMR/position_cartesian_current', '/dvrk/PSM1/position_cartesian_current']
    topics += list(PEDAL_TOPICS.values())
    topics += ['/mesa_%s/jaw_target' % s for s in SIDES] + ['/mesa_%s/joint_states' % s for s in SIDES]
    topics += ['/touchball/%s/state' % s for s in SIDES]
    paths = recording_bags(bag_path)
    with open_bags(paths) as bags:
        t0 = start_time(bags) or 0.0
        data = read_series(bags, topics)
    rep = Report(out_dir, t0)
    for side in SIDES:
        rep.figure('trajectory_%s.png' % side, 'Master vs slave trajectory, %s channel' % side,
                   lambda: plot_trajectories(data, side, scale, t0),
                   '/teleop/%s/master_pose (scaled by %.2f), /mesa_%s/target_pose, /mesa_%s/ee_pose'
                   % (side, scale, side, side))
    rep.figure('console_trajectory.png', 'da Vinci console: MTM vs PSM trajectory and foot pedals',
               lambda: plot_console(data, t0),
               '/dvrk/MTMR and /dvrk/PSM1 position_cartesian_current; shaded: /dvrk/footpedals/* pressed '
               '(clutch: PSM holds while the hand re-centres)')
    rep.figure('jaw.png', 'Instrument jaw (Simball clip)', lambda: plot_jaw(data, t0),
               '/touchball/<side>/state clip_angle, /mesa_<side>/jaw_target (scaled, clamped, rate-limited) '
               'and the measured jaw of /mesa_<side>/joint_states')
    rep.figure('distances.png', 'Tool distances', lambda: plot_distances(data, thresholds, t0),
               '/collision/distances with the collision (red) and warning (orange) thresholds')
    occ = colour_occupancy(data.get('/collision/distances', []), thresholds)
    if occ:
        rep.sections.append(('Visual feedback colours over the run', occupancy_html(occ)))
    rep.figure('energies.png', 'Tank energies', lambda: plot_energies(data, t0, limits),
               '/teleop/tank_master/energy and /teleop/tank_slave/energy')
    contact_sections(rep, data, t0, bag_path, out_dir, params)
    for title, rel, caption in (extras or []):
        if rel and rel.endswith('.txt') and os.path.exists(os.path.join(out_dir, rel)):
            with open(os.path.join(out_dir, rel)) as stream:
                text = stream.read()
            rep.sections.append((title, '<pre>%s</pre><p>%s</p>' % (html.escape(text), html.escape(caption))))
        elif rel and os.path.exists(os.path.join(out_dir, rel)):
            rep.sections.append((title, '<img src="%s" alt="%s"/><p>%s</p>' % (
                rel, html.escape(title), html.escape(caption))))
        else:
            rep.sections.append((title, '<p class="missing">not captured: %s</p>' % html.escape(caption)))
    problems = check.get('problems', []) if check else []
    body = ['<h1>SARAS MULTIROBOTS-SURGERY platform: demo report</h1>',
            '<p>Recording: %s</p>' % ' + '.join('<code>%s</code>' % html.escape(os.path.abspath(p)) for p in paths),
            '<p>%s</p>' % html.escape(summary)]
    if problems:
        body.append('<h2>Problems</h2><ul>%s</ul>' % ''.join(
            '<li class="missing">%s</li>' % html.escape(p) for p in problems))
    for title, content in list(sections) + rep.sections:
        body.append('<h2>%s</h2>%s' % (html.escape(title), content))
    if check:
        body.append('<h2>Recorded topics</h2>' + topic_table_html(check.get('results', [])))
    index = os.path.join(out_dir, 'index.html')
    with open(index, 'w') as stream:
        stream.write('<!DOCTYPE html><html><head><meta charset="utf-8"><title>SARAS demo report</title>'
                     '<style>%s</style></head><body>%s</body></html>' % (CSS, '\n'.join(body)))
    return index
