"""Receiver core: fuzzing, source filter, sequence handling, watchdog, twist estimation,
force-command latch."""
import math
import random
import struct

import pytest

from saras_drivers import touchball_protocol as tp
from saras_drivers.touchball_link import TouchballLink, TwistEstimator, WrenchLatch

SRC = '10.0.0.5'


def _dev(p=(0.0, 0.0, 0.1), q=(0.0, 0.0, 0.0, 1.0)):
    return tp.DeviceState(p, q, 0.2, False, False)


def _pkt(seq, t=None):
    return tp.pack_state(seq, seq * 0.001 if t is None else t, (_dev(), _dev()))


def test_accepts_valid_stream_and_counts_gaps():
    link = TouchballLink(SRC)
    for i, seq in enumerate([0, 1, 2, 5, 6]):
        assert link.handle_datagram(_pkt(seq), SRC, i * 0.001) is not None
    assert link.received == 5 and link.gaps == 2 and link.rejected_total == 0


def test_fuzz_never_raises_and_counts_every_rejection():
    rng = random.Random(1234)
    link = TouchballLink(SRC)
    assert link.handle_datagram(_pkt(1000), SRC, 0.0)
    good = _pkt(1001)
    sent = 0
    cases = []
    for _ in range(2000):
        cases.append(bytes(rng.getrandbits(8) for _ in range(rng.choice([0, 1, 20, 159, 160, 161, 400]))))
    for n in range(0, 160, 7):
        cases.append(good[:n])                                 # truncated
    for i in range(200):                                       # single bit flips => CRC (or header) error
        b = bytearray(good)
        k = rng.randrange(len(b))
        b[k] ^= 1 << rng.randrange(8)
        cases.append(bytes(b))
    body = good[:4] + b'\x07' + good[5:-4]
    cases.append(body + struct.pack('<I', __import__('zlib').crc32(body)))   # wrong version, valid CRC
    cases += [_pkt(1000), _pkt(999), _pkt(5)]                  # replayed and reordered
    for data in cases:
        sent += 1
        assert link.handle_datagram(data, SRC, 0.001) is None
    foreign = link.handle_datagram(good, '10.0.0.6', 0.001)    # right packet, wrong source
    assert foreign is None
    sent += 1
    assert link.received == 1
    assert link.rejected_total == sent
    for reason in ('size', 'crc', 'version', 'duplicate', 'out_of_order', 'foreign_source'):
        assert link.rejected[reason] > 0, reason
    assert link.rejected['foreign_source'] == 1
    assert link.rejected['duplicate'] == 1 and link.rejected['out_of_order'] == 2
    # the good packet is still accepted afterwards
    assert link.handle_datagram(good, SRC, 0.002) is not None


def test_any_source_when_not_configured():
    link = TouchballLink('')
    assert link.handle_datagram(_pkt(1), '192.168.1.1', 0.0) is not None


def test_watchdog_and_resync_after_console_restart():
    link = TouchballLink(SRC, timeout=0.03, resync_after=0.5)
    assert link.is_stale(0.0)                                  # nothing received yet
    link.handle_datagram(_pkt(500), SRC, 1.0)
    assert not link.is_stale(1.029)
    assert link.is_stale(1.031)
    assert link.handle_datagram(_pkt(3, t=2.0), SRC, 1.2) is None  # restart too soon: out of order
    assert link.handle_datagram(_pkt(499), SRC, 1.6) is None   # replay after silence: old sender time
    assert link.rejected['out_of_order'] == 2
    assert link.handle_datagram(_pkt(3, t=2.0), SRC, 1.7) is not None  # restarted console accepted
    assert link.handle_datagram(_pkt(4, t=2.001), SRC, 1.701) is not None


def test_invalid_parameters():
    with pytest.raises(ValueError):
        TouchballLink(SRC, timeout=0.0)
    with pytest.raises(ValueError):
        TouchballLink(SRC, timeout=0.1, resync_after=0.05)


def test_twist_of_constant_screw_motion():
    est = TwistEstimator(cutoff_hz=0.0)
    v = (0.05, -0.02, 0.01)
    w = 0.8                                                    # rad/s about z
    for k in range(50):
        t = k * 0.001
        p = tuple(c * t for c in v)
        q = (0.0, 0.0, math.sin(w * t / 2), math.cos(w * t / 2))
        lin, ang = est.update(t, p, q)
    assert lin == pytest.approx(v, abs=1e-9)
    assert ang == pytest.approx((0.0, 0.0, w), abs=1e-9)


def test_twist_rotation_axis_in_base_frame():
    # rotation about base x applied on top of a 90 deg yaw: angular velocity stays along base x.
    est = TwistEstimator(cutoff_hz=0.0)
    yaw = (0.0, 0.0, math.sin(math.pi / 4), math.cos(math.pi / 4))
    from saras_drivers.touchball_link import quat_mul
    for k in range(3):
        a = 0.5 * k * 0.001
        rx = (math.sin(a / 2), 0.0, 0.0, math.cos(a / 2))
        lin, ang = est.update(k * 0.001, (0, 0, 0), quat_mul(rx, yaw))
    assert ang == pytest.approx((0.5, 0.0, 0.0), abs=1e-9)


def test_twist_filter_converges_and_resets_on_gap():
    est = TwistEstimator(cutoff_hz=20.0, max_dt=0.05)
    for k in range(400):
        lin, _ = est.update(k * 0.001, (0.1 * k * 0.001, 0, 0), (0, 0, 0, 1))
    assert lin[0] == pytest.approx(0.1, rel=1e-6)
    lin, _ = est.update(10.0, (0, 0, 0), (0, 0, 0, 1))
    assert lin == (0.0, 0.0, 0.0)


def test_wrench_latch_clamps_ages_and_rejects_nan():
    latch = WrenchLatch(max_force=3.0, max_torque=0.0, max_age=0.1)
    assert latch.get(0.0) == tp.ZERO_COMMAND
    assert latch.set((6.0, 8.0, 0.0), (1.0, 0.0, 0.0), 1.0)
    c = latch.get(1.05)
    assert c.enabled and c.force == pytest.approx((1.8, 2.4, 0.0)) and c.torque == (0.0, 0.0, 0.0)
    assert latch.get(1.11) == tp.ZERO_COMMAND
    assert not latch.set((float('nan'), 0, 0), (0, 0, 0), 2.0)
    assert latch.get(2.0) == tp.ZERO_COMMAND and latch.rejected == 1


def _reference_twist(samples, cutoff_hz):
    """Vector form of the estimator (quat_mul / quat_log_vec), independent of the scalar code."""
    from saras_drivers.touchball_link import quat_conj, quat_log_vec
    tau = 1.0 / (2.0 * math.pi * cutoff_hz)
    lin, ang = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    from saras_drivers.touchball_link import quat_mul
    for (t0, p0, q0), (t1, p1, q1) in zip(samples, samples[1:]):
        dt = t1 - t0
        v = [(b - a) / dt for a, b in zip(p0, p1)]
        w = [c / dt for c in quat_log_vec(quat_mul(q1, quat_conj(q0)))]
        a = dt / (dt + tau)
        lin = tuple(l + a * (n - l) for l, n in zip(lin, v))
        ang = tuple(l + a * (n - l) for l, n in zip(ang, w))
    return lin, ang


def test_scalar_twist_matches_vector_reference_on_random_motion():
    rng = random.Random(3)
    samples = []
    for k in range(200):
        t = k * 0.001 + rng.uniform(0, 2e-4)
        q = [math.sin(0.3 * t + i) for i in range(4)]
        n = math.sqrt(sum(x * x for x in q))
        if k % 50 == 7:
            q = [-x for x in q]                                # same rotation, other hemisphere
        samples.append((t, tuple(rng.uniform(-0.1, 0.1) for _ in range(3)), tuple(x / n for x in q)))
    est = TwistEstimator(cutoff_hz=40.0)
    for t, p, q in samples:
        lin, ang = est.update(t, p, q)
    rlin, rang = _reference_twist(samples, 40.0)
    assert lin == pytest.approx(rlin, rel=1e-9, abs=1e-12)
    assert ang == pytest.approx(rang, rel=1e-9, abs=1e-12)


def test_accept_fast_path_state_and_last_packet():
    link = TouchballLink(SRC)
    assert link.accept(_pkt(7), SRC, 0.0) and link.seq == 7 and link.gap == 0
    assert link.devices[0][:7] == (0.0, 0.0, 0.1, 0.0, 0.0, 0.0, 1.0)
    assert link.last_packet == tp.unpack_state(_pkt(7))
    assert not link.accept(b'garbage', SRC, 0.001) and link.rejected['size'] == 1
    assert not link.accept(None, SRC, 0.001) and link.rejected['size'] == 2   # not even bytes
    assert link.seq == 7 and link.received == 1                 # rejected input changed nothing
