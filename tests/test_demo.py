"""End-to-end: `scripts/demo.sh` brings the whole simulated platform up, records every stream of
the deliverable's recording list, and writes the report (plots, augmented stereo frame, rviz
screenshot of the replayed recording, topic table); both tools press into the tissue and the
stereo contact estimate sees it (report/contact.json).

Everywhere: every required stream is recorded, every required periodic stream reaches the
`min_rate_fraction` (80 %) of the rate the demo configured it at (`nominal_rate` in topics.json:
recording.yaml's rate, "control" streams at the demo's CONTROL_RATE), and the demo's exit status
agrees with its bag check. On machines with >= 4 cores the demo must also pass its full bag check
(no lost messages), i.e. exit 0. On smaller machines scripts/demo.sh lowers the control rate and the
endoscope size (README "Known limitations"); a stream that then drops a message is reported by the
demo but does not fail this test, a stream below 80 % of its configured rate does."""
import json
import os
import subprocess

import yaml

WS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# 32 s: the scripted surgeon dips every 12 s for 8 s (touchball_console_sim's dip_period and
# dip_duration), so a 32 s recording holds two whole dips of each tool whatever its phase (12 + 12 + 8);
# a hold on a loaded host (the operator clutches, the dip's motion is lost) costs one of them. A 20 s
# recording holds one: a held dip left a tool 0.07 mm deep.
DURATION = int(os.environ.get('SARAS_TEST_DEMO_DURATION', '32'))
RECORDING = os.path.join(WS, 'src', 'saras_bringup', 'config', 'recording.yaml')


def min_rate_fraction():
    """The fraction of the configured rate a required stream must reach (recording.yaml)."""
    with open(RECORDING) as f:
        return float(yaml.safe_load(f).get('min_rate_fraction', 0.8))


def test_demo_records_every_required_stream_and_writes_the_report(tmp_path):
    out = tmp_path / 'demo'
    proc = subprocess.run(['bash', os.path.join(WS, 'scripts', 'demo.sh'), str(DURATION), str(out)],
                          capture_output=True, text=True, timeout=DURATION + 600)
    log = proc.stdout[-6000:] + proc.stderr[-3000:]
    assert proc.returncode in (0, 1), log            # 2 = the platform did not come up
    assert (out / 'platform.bag').exists(), log
    with open(out / 'report' / 'topics.json') as f:
        check = json.load(f)
    rows = [r for r in check['results'] if r['required']]
    assert rows
    fraction = min_rate_fraction()
    slow = ['%s at %.1f Hz (configured %.0f Hz)' % (r['topic'], r['rate'], r['nominal_rate'])
            for r in rows if r['nominal_rate'] > 0 and r['rate'] < fraction * r['nominal_rate']]
    missing = [r['topic'] for r in rows if r['count'] == 0]
    assert not missing, 'required streams not recorded: %s\n%s' % (missing, log)
    assert not slow, 'required streams below %.0f %% of their rate: %s\n%s' % (100 * fraction, slow, log)
    assert (proc.returncode == 0) == (check['problems'] == []), log
    if len(os.sched_getaffinity(0)) >= 4:   # the cores demo.sh sees (nproc)
        assert proc.returncode == 0, log
    report = out / 'report'
    html = (report / 'index.html').read_text()
    for png in ('trajectory_left.png', 'trajectory_right.png', 'distances.png', 'energies.png',
                'contact_forces.png', 'augmented_stereo.png', 'rviz.png', 'operator_view.png', 'jaw.png'):
        assert (report / png).exists() and (report / png).stat().st_size > 10000, png
        assert png in html
    assert 'not recorded:' not in html and 'not captured:' not in html
    # the operator view page (saras_operator_view) showed live frames in headless Chromium
    page = json.loads((report / 'operator_view.json').read_text())
    assert page.get('live') is True, page
    # the calibration accuracy table (robust hand-eye vs OpenCV's methods) is part of the report
    assert '| robust |' in html and '| tsai |' in html
    # D7.2 Section 8: the scripted surgeon's dips press both tools into the tissue (at least one of them
    # 1 mm deep), and the stereo estimate sees those contacts (known, not unknown) and follows their depth.
    contact = json.loads((report / 'contact.json').read_text())
    pressed = [s for s, c in contact.items() if c['truth_contact'] >= 10 and c['max_true_mm'] >= 0.5]
    assert sorted(pressed) == ['left', 'right'], 'not both tools pressed into the tissue: %s' % contact
    assert max(c['max_true_mm'] for c in contact.values()) >= 1.0, contact
    for side in pressed:
        c = contact[side]
        assert c['known_in_contact'] >= 0.5 * c['truth_contact'], '%s contact not seen by the estimator: %s' % (side, c)
        assert c['rms_contact_mm'] < 1.5, '%s estimated depth far from the truth in contact: %s' % (side, c)
