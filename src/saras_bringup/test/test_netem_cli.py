"""The netem_relay command (ROS-free mode): relays, prints counters, writes them at exit."""
import json
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

SCRIPT = Path(__file__).resolve().parents[1] / 'scripts' / 'netem_relay'


def free_udp_port():
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(('127.0.0.1', 0))
    port = s.getsockname()[1]
    s.close()
    return port


def test_cli_relays_and_reports(tmp_path):
    sink = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sink.bind(('127.0.0.1', 0))
    sink.settimeout(5)
    listen = free_udp_port()
    links = tmp_path / 'links.yaml'
    links.write_text('links:\n  - {name: probe, protocol: udp, listen: "127.0.0.1:%d", '
                     'target: "127.0.0.1:%d", delay_ms: 10, loss: 0.5, seed: 2}\n'
                     % (listen, sink.getsockname()[1]))
    out = tmp_path / 'counters.json'
    relay = subprocess.Popen([sys.executable, str(SCRIPT), str(links), '--period', '0.2',
                              '--json', str(out)], stdout=subprocess.PIPE, text=True)
    try:
        assert 'listening on 127.0.0.1:%d' % listen in relay.stdout.readline()
        sender = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        for _ in range(200):
            sender.sendto(b'x', ('127.0.0.1', listen))
            time.sleep(0.001)
        received = 0
        try:
            while True:
                sink.recvfrom(10)
                received += 1
                sink.settimeout(1.0)
        except socket.timeout:
            pass
    finally:
        relay.send_signal(signal.SIGINT)
        stdout, _ = relay.communicate(timeout=20)
    assert relay.returncode == 0
    forward = json.loads(out.read_text())['probe']['forward']
    assert forward['received'] == 200 and forward['sent'] == received
    assert 60 <= forward['dropped'] <= 140  # binomial(200, 0.5): 100 +- 5.7 sigma
    assert forward['delay_min_ms'] >= 10.0
    assert 'probe' in stdout and 'drop' in stdout


def test_cli_rejects_a_bad_links_file(tmp_path):
    links = tmp_path / 'links.yaml'
    links.write_text('links:\n  - {name: a, protocol: tcp, listen: "127.0.0.1:0", '
                     'target: "127.0.0.1:1", loss: 0.1}\n')
    r = subprocess.run([sys.executable, str(SCRIPT), str(links)], stderr=subprocess.PIPE,
                       text=True, timeout=30)
    assert r.returncode == 1 and 'not applicable to tcp' in r.stderr
