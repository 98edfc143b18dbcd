"""End-to-end: the demo brings the whole simulated platform up, records every required stream at
its nominal rate without lost messages, and writes the report (plots, augmented frame, rviz)."""
import json
import os
import subprocess

WS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DURATION = int(os.environ.get('SARAS_TEST_DEMO_DURATION', '25'))


def test_demo_records_every_required_stream_and_writes_the_report(tmp_path):
    out = tmp_path / 'demo'
    proc = subprocess.run(['bash', os.path.join(WS, 'scripts', 'demo.sh'), str(DURATION), str(out)],
                          capture_output=True, text=True, timeout=DURATION + 240)
    log = proc.stdout[-6000:] + proc.stderr[-3000:]
    assert (out / 'platform.bag').exists(), log
    with open(out / 'report' / 'topics.json') as f:
        check = json.load(f)
    assert check['problems'] == [], log
    assert proc.returncode == 0, log
    rows = {r['topic']: r for r in check['results']}
    # a few streams checked explicitly against their nominal rates
    assert rows['/touchball/left/state']['rate'] > 800
    assert rows['/collision/distances']['rate'] > 16
    assert rows['/endoscope/left/image_raw/compressed']['rate'] > 24
    report = out / 'report'
    html = (report / 'index.html').read_text()
    for png in ('trajectory_left.png', 'trajectory_right.png', 'distances.png', 'energies.png',
                'augmented_stereo.png', 'rviz.png'):
        assert (report / png).exists() and (report / png).stat().st_size > 10000, png
        assert png in html
    assert 'not recorded' not in html and 'not captured' not in html
