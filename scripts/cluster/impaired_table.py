#!/usr/bin/env python3
"""Table (markdown + HTML with the energy plots) of the impaired-network runs of cluster_impaired.sh.

  scripts/cluster/impaired_table.py OUT CASE...     (reads OUT/<case>/energy.json and
  OUT/<case>/report/topics.json (bag_check), writes OUT/table.md, OUT/index.html)
"""
import html
import json
import os
import re
import sys

COLUMNS = [('case', '%s'), ('e0_J', '%.2f'), ('entered_J', '%.3f'), ('delivered_J', '%.3f'),
           ('net_max_J', '%.3f'), ('passive', '%s'), ('tracking_rms_mm_left', '%.2f'),
           ('tracking_rms_mm_right', '%.2f'), ('time_to_hold_s_left', '%s'), ('time_to_hold_s_right', '%s'),
           ('robot_hold_s_left', '%s'), ('robot_hold_s_right', '%s'), ('recorder_lag_s', '%s'),
           ('slave_travel_mm_left', '%.1f'), ('slave_travel_mm_right', '%.1f'), ('contact_max_N_left', '%.1f'), ('contact_max_N_right', '%.1f'), ('contact_s', '%.1f'),
           ('bag_check', '%s')]
HEAD = ['case', 'E0 [J]', 'entered [J]', 'delivered [J]', 'max net out [J]', 'passive',
        'tracking RMS L [mm]', 'tracking RMS R [mm]', 'set-point hold L [s]', 'set-point hold R [s]',
        'robot still L [s]', 'robot still R [s]', 'recorder lag [s]', 'slave travel L [mm]', 'slave travel R [mm]', 'contact max L [N]', 'contact max R [N]',
        'in contact L+R [s]', 'bag_check']


def cell(row, key, fmt):
    v = row.get(key)
    if v is None:
        return '-'
    if isinstance(v, float) and fmt == '%s':
        return '%.3f' % v
    return fmt % v


def bag_check_summary(path):
    """'ok', or the problems of bag_check's JSON shortened to 'topic rate' / the machine line."""
    if not os.path.exists(path):
        return 'no result'
    with open(path) as stream:
        problems = json.load(stream).get('problems', [])
    if not problems:
        return 'ok'
    short = []
    for p in problems:
        rate = re.search(r'rate ([0-9.]+) Hz', p)
        skew = re.search(r'^machine (\S+): header stamps ([0-9.]+) ms (ahead|behind)', p)
        if skew:
            short.append('%s stamps %s ms %s' % skew.groups())
        else:
            short.append(p.split(' (')[0] + (' %s Hz' % rate.group(1) if rate else ''))
    more = ' (+%d more)' % (len(short) - 4) if len(short) > 4 else ''
    return '%d: %s%s' % (len(short), '; '.join(short[:4]), more)


def main(out, cases):
    rows = []
    for c in cases:
        path = os.path.join(out, c, 'energy.json')
        if os.path.exists(path):
            with open(path) as stream:
                row = json.load(stream)
        else:
            row = {'case': c}
        row['case'] = c
        if 'contact_s_left' in row:
            row['contact_s'] = row['contact_s_left'] + row.get('contact_s_right', 0.0)
        lags = [row[k] for k in ('recorder_lag_s_left', 'recorder_lag_s_right') if row.get(k) is not None]
        row['recorder_lag_s'] = max(lags) if lags else None
        row['bag_check'] = bag_check_summary(os.path.join(out, c, 'report', 'topics.json'))
        rows.append(row)
    md = ['| ' + ' | '.join(HEAD) + ' |', '|' + '---|' * len(HEAD)]
    md += ['| ' + ' | '.join(cell(r, k, f) for k, f in COLUMNS) + ' |' for r in rows]
    with open(os.path.join(out, 'table.md'), 'w') as stream:
        stream.write('\n'.join(md) + '\n')
    body = ['<h1>Teleoperation across impaired links</h1>',
            '<p>entered = E0 (initial tank energy; 0 bypassed) + energy injected at the ports; '
            'passive = the net energy out of the teleoperator never exceeded E0.</p>',
            '<table><tr>%s</tr>%s</table>' % (''.join('<th>%s</th>' % html.escape(h) for h in HEAD), ''.join(
                '<tr>%s</tr>' % ''.join('<td>%s</td>' % html.escape(cell(r, k, f)) for k, f in COLUMNS)
                for r in rows))]
    for r in rows:
        if os.path.exists(os.path.join(out, r['case'] + '.png')):
            body.append('<h2>%s</h2><img src="%s.png"/><p><a href="%s/report/index.html">cluster report</a></p>'
                        % (html.escape(r['case']), html.escape(r['case']), html.escape(r['case'])))
    with open(os.path.join(out, 'index.html'), 'w') as stream:
        stream.write('<!DOCTYPE html><html><head><meta charset="utf-8"><style>table{border-collapse:collapse}'
                     'td,th{border:1px solid #ccc;padding:2px 6px}</style></head><body>%s</body></html>'
                     % '\n'.join(body))
    print('\n'.join(md))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1], sys.argv[2:]))
