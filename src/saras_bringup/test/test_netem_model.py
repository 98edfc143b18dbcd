"""Impairment model and links-file parser of the user-space netem (saras_bringup.netem).

Statistics are checked against their distributions with wide bounds (5 sigma or more), on seeded
generators so that a failure is reproducible; several seeds guard against a lucky one.
"""
import math

import pytest

from saras_bringup.netem import Impairment, ImpairmentConfig, LinkStats, parse_links


def binomial_bounds(n, p, sigmas=5.0):
    sd = math.sqrt(n * p * (1.0 - p))
    return n * p - sigmas * sd, n * p + sigmas * sd


@pytest.mark.parametrize('seed', [1, 2, 3])
def test_random_loss_within_binomial_bounds(seed):
    n, p = 20000, 0.10
    imp = Impairment(ImpairmentConfig(loss=p), seed)
    dropped = sum(imp.drop() for _ in range(n))
    low, high = binomial_bounds(n, p)
    assert low <= dropped <= high


def loss_runs(drops):
    """Lengths of the runs of consecutive losses."""
    runs, run = [], 0
    for d in drops:
        if d:
            run += 1
        elif run:
            runs.append(run)
            run = 0
    return runs + ([run] if run else [])


@pytest.mark.parametrize('seed', [4, 5])
def test_gilbert_elliott_loss_is_bursty_with_the_documented_means(seed):
    cfg = ImpairmentConfig(p_good_bad=0.01, p_bad_good=0.25, loss_good=0.0, loss_bad=1.0)
    imp = Impairment(cfg, seed)
    drops = [imp.drop() for _ in range(200000)]
    rate = sum(drops) / len(drops)
    assert cfg.expected_loss() == pytest.approx(0.01 / 0.26)
    assert rate == pytest.approx(cfg.expected_loss(), rel=0.15)
    runs = loss_runs(drops)
    assert sum(runs) / len(runs) == pytest.approx(1.0 / 0.25, rel=0.1)  # mean burst 1/p_bad_good
    after_loss = sum(1 for a, b in zip(drops, drops[1:]) if a and b) / sum(drops[:-1])
    assert after_loss == pytest.approx(0.75, abs=0.03)  # P(loss | loss) = 1 - p_bad_good >> rate


def test_random_loss_is_not_bursty():
    imp = Impairment(ImpairmentConfig(loss=0.04), 6)
    drops = [imp.drop() for _ in range(100000)]
    after_loss = sum(1 for a, b in zip(drops, drops[1:]) if a and b) / sum(drops[:-1])
    assert after_loss < 0.08


def test_random_and_bursty_loss_combine():
    cfg = ImpairmentConfig(loss=0.1, p_good_bad=0.02, p_bad_good=0.5, loss_bad=0.5)
    imp = Impairment(cfg, 7)
    n = 100000
    rate = sum(imp.drop() for _ in range(n)) / n
    pi_bad = 0.02 / 0.52
    assert cfg.expected_loss() == pytest.approx(1 - 0.9 * (1 - 0.5 * pi_bad))
    assert rate == pytest.approx(cfg.expected_loss(), rel=0.1)


@pytest.mark.parametrize('distribution', ['uniform', 'normal'])
def test_jitter_is_bounded_and_centred(distribution):
    imp = Impairment(ImpairmentConfig(delay_s=0.050, jitter_s=0.010,
                                      jitter_distribution=distribution), 8)
    delays = [imp.delay() for _ in range(20000)]
    assert 0.040 <= min(delays) and max(delays) <= 0.060
    assert sum(delays) / len(delays) == pytest.approx(0.050, abs=0.0005)
    spread = max(delays) - min(delays)
    assert spread > 0.015  # jitter actually applied


def test_delay_never_negative_and_fixed_without_jitter():
    imp = Impairment(ImpairmentConfig(delay_s=0.002, jitter_s=0.010), 9)
    assert min(imp.delay() for _ in range(5000)) >= 0.0
    assert Impairment(ImpairmentConfig(delay_s=0.02)).delay() == 0.02


def test_stream_release_keeps_order_under_jitter():
    imp = Impairment(ImpairmentConfig(delay_s=0.030, jitter_s=0.020), 10)
    releases = [imp.stream_release(0.001 * i) for i in range(2000)]
    assert releases == sorted(releases)
    assert all(r >= 0.001 * i + 0.010 for i, r in enumerate(releases))


def test_explicit_reordering_holds_the_configured_share():
    cfg = ImpairmentConfig(delay_s=0.010, reorder_probability=0.2, reorder_gap_s=0.005)
    imp = Impairment(cfg, 11)
    releases = [imp.datagram_release(0.0) for _ in range(20000)]
    held = sum(1 for r in releases if r > 0.0125)
    low, high = binomial_bounds(20000, 0.2)
    assert low <= held <= high


def test_stats_count_reordering_and_histogram():
    stats = LinkStats()
    seqs = [stats.on_received() for _ in range(5)]
    for seq, delay in zip([0, 2, 1, 3, 4], [0.0005, 0.003, 0.003, 0.07, 2.0]):
        stats.on_sent(seq, delay, 10)
    stats.on_dropped()
    d = stats.as_dict()
    assert seqs == [0, 1, 2, 3, 4]
    assert (d['sent'], d['dropped'], d['reordered'], d['bytes_sent']) == (5, 1, 1, 50)
    assert d['delay_histogram_ms'] == {'<1': 1, '<2': 0, '<5': 2, '<10': 0, '<20': 0, '<50': 0,
                                       '<100': 1, '<200': 0, '<500': 0, '<1000': 0, '>=1000': 1}
    assert d['delay_min_ms'] == pytest.approx(0.5) and d['delay_max_ms'] == pytest.approx(2000)


@pytest.mark.parametrize('kwargs, message', [
    ({'loss': 1.5}, 'probability'),
    ({'delay_s': -0.001}, '>= 0'),
    ({'jitter_distribution': 'pareto'}, 'uniform'),
    ({'p_good_bad': 0.1, 'p_bad_good': 0.0}, 'trap'),
    ({'reorder_probability': 0.1}, 'reorder_gap_s'),
])
def test_config_rejects_invalid_values(kwargs, message):
    with pytest.raises(ValueError, match=message):
        ImpairmentConfig(**kwargs)


EXAMPLE = {'links': [
    {'name': 'console', 'protocol': 'udp', 'listen': '10.77.0.13:16000',
     'target': '10.77.0.11:6000', 'source': '10.77.0.13:0', 'seed': 1, 'delay_ms': 50,
     'jitter_ms': 5, 'loss': 0.1, 'burst': {'p_good_bad': 0.01, 'p_bad_good': 0.25},
     'reorder': {'probability': 0.05, 'gap_ms': 10}, 'reverse': {'delay_ms': 20}},
    {'name': 'arm', 'protocol': 'tcp', 'listen': '127.0.0.1:0', 'target': 'localhost:8080',
     'delay_ms': 200, 'jitter_ms': 10, 'jitter_distribution': 'normal'},
]}


def test_links_file_parses_with_units():
    console, arm = parse_links(EXAMPLE)
    assert console.listen == ('10.77.0.13', 16000) and console.source == ('10.77.0.13', 0)
    assert console.forward.delay_s == pytest.approx(0.050)
    assert console.forward.p_good_bad == 0.01 and console.forward.reorder_gap_s == 0.010
    assert console.reverse.delay_s == pytest.approx(0.020) and console.reverse.loss == 0.0
    assert arm.protocol == 'tcp' and arm.source is None and arm.reverse.delay_s == 0.0
    assert arm.forward.jitter_distribution == 'normal'


@pytest.mark.parametrize('change, message', [
    ({'loss': 0.1}, 'not applicable to tcp'),
    ({'delay': 5}, 'unknown keys'),
    ({'listen': '127.0.0.1'}, 'host:port'),
    ({'protocol': 'sctp'}, "'udp' or 'tcp'"),
    ({'reverse': {'burst': {'p': 1}}}, r"reverse: \['burst'\] not applicable to tcp"),
    ({'protocol': 'udp', 'reverse': {'burst': {'p': 1}}}, r'reverse.burst: unknown keys'),
])
def test_links_file_errors_name_the_key(change, message):
    arm = dict(EXAMPLE['links'][1], **change)
    with pytest.raises(ValueError, match=message):
        parse_links({'links': [arm]})


def test_links_file_rejects_duplicate_names():
    with pytest.raises(ValueError, match='duplicate'):
        parse_links({'links': [EXAMPLE['links'][1], EXAMPLE['links'][1]]})
