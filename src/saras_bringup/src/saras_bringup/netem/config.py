"""Link configuration of the impairment relay, read from YAML (ROS-free).

A links file holds a list ``links``; each link relays one protocol from ``listen`` to ``target``::

    links:
      - name: console_to_teleop        # unique, used in counters and diagnostics
        protocol: udp                  # udp | tcp
        listen: 10.77.0.13:16000       # where the sender sends to (host:port)
        target: 10.77.0.11:6000        # where the relay delivers (host:port)
        source: 10.77.0.13:0           # optional: local address the relay sends from
                                       #   (port 0: any; a fixed port allows one UDP client)
        seed: 1                        # optional: random seed (reproducible runs)
        delay_ms: 50                   # one-way delay [ms]
        jitter_ms: 5                   # bounded jitter around the delay [ms]
        jitter_distribution: uniform   # uniform | normal (sigma = jitter/2, truncated at +-jitter)
        loss: 0.10                     # random loss probability [0..1] (udp only)
        burst:                         # Gilbert-Elliott bursty loss (udp only), per packet:
          p_good_bad: 0.01             #   P(Good -> Bad)
          p_bad_good: 0.25             #   P(Bad -> Good); mean burst 1/p_bad_good packets
          loss_good: 0.0               #   loss probability in Good
          loss_bad: 1.0                #   loss probability in Bad
        reorder:                       # explicit reordering (udp only)
          probability: 0.05            #   share of packets held back
          gap_ms: 10                   #   extra delay of a held-back packet [ms]
        reverse:                       # optional: the same keys for replies target -> sender;
          delay_ms: 50                 #   absent: replies are relayed unimpaired

TCP links take only delay and jitter (a byte stream has no packets to lose or reorder).
"""
from dataclasses import dataclass
from typing import Optional, Tuple

from .impairment import ImpairmentConfig

_IMPAIRMENT_KEYS = {'delay_ms', 'jitter_ms', 'jitter_distribution', 'loss', 'burst', 'reorder'}
_LINK_KEYS = {'name', 'protocol', 'listen', 'target', 'source', 'seed', 'reverse'}
_BURST_KEYS = {'p_good_bad', 'p_bad_good', 'loss_good', 'loss_bad'}
_REORDER_KEYS = {'probability', 'gap_ms'}


@dataclass(frozen=True)
class LinkConfig:
    name: str
    protocol: str
    listen: Tuple[str, int]
    target: Tuple[str, int]
    source: Optional[Tuple[str, int]]
    forward: ImpairmentConfig
    reverse: ImpairmentConfig
    seed: Optional[int] = None


def parse_endpoint(text, where):
    """'host:port' -> (host, port)."""
    host, sep, port = str(text).rpartition(':')
    if not sep or not host or not port.isdigit() or int(port) > 65535:
        raise ValueError('%s = %r: host:port expected' % (where, text))
    return host, int(port)


def _check_keys(mapping, allowed, where):
    if not isinstance(mapping, dict):
        raise ValueError('%s: a mapping expected, got %r' % (where, mapping))
    unknown = set(mapping) - allowed
    if unknown:
        raise ValueError('%s: unknown keys %s (allowed: %s)'
                         % (where, sorted(unknown), sorted(allowed)))


def parse_impairment(spec, protocol, where):
    """The impairment keys of a link (or of its ``reverse``) -> ImpairmentConfig."""
    _check_keys(spec, _IMPAIRMENT_KEYS, where)
    if protocol == 'tcp':
        bad = sorted(k for k in ('loss', 'burst', 'reorder') if k in spec)
        if bad:
            raise ValueError('%s: %s not applicable to tcp (a stream keeps every byte in order)'
                             % (where, bad))
    burst = spec.get('burst', {})
    reorder = spec.get('reorder', {})
    _check_keys(burst, _BURST_KEYS, where + '.burst')
    _check_keys(reorder, _REORDER_KEYS, where + '.reorder')
    try:
        return ImpairmentConfig(
            delay_s=1e-3 * float(spec.get('delay_ms', 0.0)),
            jitter_s=1e-3 * float(spec.get('jitter_ms', 0.0)),
            jitter_distribution=spec.get('jitter_distribution', 'uniform'),
            loss=float(spec.get('loss', 0.0)),
            p_good_bad=float(burst.get('p_good_bad', 0.0)),
            p_bad_good=float(burst.get('p_bad_good', 1.0)),
            loss_good=float(burst.get('loss_good', 0.0)),
            loss_bad=float(burst.get('loss_bad', 1.0)),
            reorder_probability=float(reorder.get('probability', 0.0)),
            reorder_gap_s=1e-3 * float(reorder.get('gap_ms', 0.0)))
    except (TypeError, ValueError) as e:
        raise ValueError('%s: %s' % (where, e)) from None


def parse_link(spec, index):
    where = 'links[%d]' % index
    _check_keys(spec, _LINK_KEYS | _IMPAIRMENT_KEYS, where)
    for key in ('name', 'protocol', 'listen', 'target'):
        if key not in spec:
            raise ValueError('%s: %r missing' % (where, key))
    protocol = spec['protocol']
    if protocol not in ('udp', 'tcp'):
        raise ValueError("%s.protocol = %r: 'udp' or 'tcp' expected" % (where, protocol))
    seed = spec.get('seed')
    if seed is not None and not isinstance(seed, int):
        raise ValueError('%s.seed = %r: an integer expected' % (where, seed))
    return LinkConfig(
        name=str(spec['name']), protocol=protocol,
        listen=parse_endpoint(spec['listen'], where + '.listen'),
        target=parse_endpoint(spec['target'], where + '.target'),
        source=parse_endpoint(spec['source'], where + '.source') if 'source' in spec else None,
        forward=parse_impairment({k: v for k, v in spec.items() if k in _IMPAIRMENT_KEYS},
                                 protocol, where),
        reverse=parse_impairment(spec.get('reverse', {}), protocol, where + '.reverse'),
        seed=seed)


def parse_links(document):
    """The parsed YAML document (a dict with ``links``) -> list of LinkConfig."""
    _check_keys(document, {'links'}, 'links file')
    links = document.get('links')
    if not isinstance(links, list) or not links:
        raise ValueError('links file: a non-empty list "links" expected')
    parsed = [parse_link(spec, i) for i, spec in enumerate(links)]
    names = [link.name for link in parsed]
    if len(set(names)) != len(names):
        raise ValueError('links file: duplicate link names %s' % names)
    return parsed


def load_links(path):
    import yaml
    with open(path) as f:
        return parse_links(yaml.safe_load(f))
