"""End-to-end: `scripts/demo.sh` brings the whole simulated platform up, records every stream of
the deliverable's recording list, and writes the report (plots, augmented stereo frame, rviz
screenshot of the replayed recording, topic table).

On a machine with fewer than 4 cores the ~35 processes cannot all hold their nominal rates (see
README "Resource budget"); the demo then exits 1 and names the slow streams, which is the truthful
result (README "Status and known limitations" lists the measured shortfall). This test therefore
requires everywhere that every required stream is recorded and flowing (periodic streams at >= 1 Hz)
and that the demo's exit status agrees with the bag check; the full nominal-rate check (demo exit 0)
is required on machines with >= 4 cores."""
import json
import os
import subprocess

WS = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DURATION = int(os.environ.get('SARAS_TEST_DEMO_DURATION', '20'))
MIN_FLOWING_RATE = 1.0   # [Hz] a periodic stream below this is considered not flowing at all


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
    for r in rows:
        assert r['count'] > 0, 'required stream %s not recorded\n%s' % (r['topic'], log)
        if r['nominal_rate'] > 0:
            assert r['rate'] >= MIN_FLOWING_RATE, '%s at %.1f Hz (nominal %.0f)' % (
                r['topic'], r['rate'], r['nominal_rate'])
    if os.cpu_count() >= 4:
        assert check['problems'] == [] and proc.returncode == 0, log
    else:
        assert (proc.returncode == 0) == (check['problems'] == []), log
    report = out / 'report'
    html = (report / 'index.html').read_text()
    for png in ('trajectory_left.png', 'trajectory_right.png', 'distances.png', 'energies.png',
                'contact_forces.png', 'augmented_stereo.png', 'rviz.png'):
        assert (report / png).exists() and (report / png).stat().st_size > 10000, png
        assert png in html
    assert 'not recorded:' not in html and 'not captured:' not in html
    # the calibration accuracy table (robust hand-eye vs OpenCV's methods) is part of the report
    assert '| robust |' in html and '| tsai |' in html
