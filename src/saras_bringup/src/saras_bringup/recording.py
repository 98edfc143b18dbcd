"""The recording list of the ROS core & data-recording node and the check of a recorded bag.

``load_recording_config`` validates ``config/recording.yaml``; ``recorder_command`` turns it into the
``bag_recorder`` command line (bounded buffer, explicit topic list) and ``stream_recorder_command``
into the loader of the ``saras_bringup/StreamRecorder`` nodelet, which records the streams flagged
``in_process`` inside their publishers' nodelet manager (zero-copy) into the part bag
``part_path(main bag, part)``. A recording is the main bag and its parts (``recording_bags``).
``check_bag`` measures every stream of a recording: message count, rate, sequence gaps
(``header.seq`` jumps of a single publisher) and stamp gaps (intervals longer than
``gap_factor / rate``). rosbag's own "dropped" warnings are throttled and undercount, so the bag
itself is the evidence.

Only ``open_bags`` and ``check_bag`` need the ``rosbag`` Python module; it is imported lazily.
"""
import contextlib
import glob
import heapq
import os
import re
import struct

import yaml


class RecordingConfigError(ValueError):
    """An invalid recording configuration (the message names the entry and field)."""


class Stream(object):
    __slots__ = ('topic', 'rate', 'group', 'required', 'header', 'in_process')

    def __init__(self, topic, rate, group, required, header, in_process=False):
        self.topic, self.rate, self.group = topic, rate, group
        self.required, self.header, self.in_process = required, header, in_process


class RecordingConfig(object):
    def __init__(self, streams, min_rate_fraction, gap_factor, buffer_mb, chunk_kb, queue=2000,
                 tcp_nodelay=False, in_process_manager=None, in_process_part=None):
        self.streams = streams
        self.tcp_nodelay = tcp_nodelay
        self.queue = queue
        self.min_rate_fraction = min_rate_fraction
        self.gap_factor = gap_factor
        self.buffer_mb = buffer_mb
        self.chunk_kb = chunk_kb
        self.in_process_manager = in_process_manager   # nodelet manager publishing the in_process streams
        self.in_process_part = in_process_part         # their bag: part_path(main bag, in_process_part)

    @property
    def topics(self):
        return [s.topic for s in self.streams]

    @property
    def main_topics(self):
        """Topics of the main bag (bag_recorder) when the in-process streams are recorded apart."""
        return [s.topic for s in self.streams if not s.in_process]

    @property
    def in_process_topics(self):
        """Topics recorded inside ``in_process_manager`` (StreamRecorder nodelet)."""
        return [s.topic for s in self.streams if s.in_process]


def _number(data, key, default, low, high):
    value = data.get(key, default)
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not (low <= value <= high):
        raise RecordingConfigError('"%s" must be a number in [%g, %g], got %r' % (key, low, high, value))
    return value


_ROS_NAME = re.compile(r'^(/[A-Za-z][A-Za-z0-9_]*)+$')
_PART = re.compile(r'^[A-Za-z0-9_]+$')


def _in_process_section(data):
    """(manager, part) of the optional ``in_process`` section, or (None, None)."""
    section = data.get('in_process')
    if section is None:
        return None, None
    if not isinstance(section, dict):
        raise RecordingConfigError('"in_process" must be a mapping with "manager" and "part", got %r' % (section,))
    manager, part = section.get('manager'), section.get('part')
    if not isinstance(manager, str) or not _ROS_NAME.match(manager):
        raise RecordingConfigError('in_process: "manager" must be an absolute node name, got %r' % (manager,))
    if not isinstance(part, str) or not _PART.match(part):
        raise RecordingConfigError('in_process: "part" must be a non-empty name of [A-Za-z0-9_], got %r'
                                   % (part,))
    return manager, part


def _stream_in_process(entry, i, topic, manager):
    value = entry.get('in_process', False)
    if not isinstance(value, bool):
        raise RecordingConfigError('streams[%d] (%s): "in_process" must be true or false, got %r'
                                   % (i, topic, value))
    if value and manager is None:
        raise RecordingConfigError('streams[%d] (%s): "in_process: true" needs the top-level "in_process" '
                                   'section (manager, part)' % (i, topic))
    return value


def parse_recording_config(data, control_rate=1000.0):
    """Validate a loaded recording.yaml; ``rate: control`` streams get ``control_rate`` [Hz]."""
    if not isinstance(data, dict) or not isinstance(data.get('streams'), list) or not data['streams']:
        raise RecordingConfigError('expected a mapping with a non-empty "streams" list')
    manager, part = _in_process_section(data)
    streams, seen = [], set()
    for i, entry in enumerate(data['streams']):
        if not isinstance(entry, dict):
            raise RecordingConfigError('streams[%d] is not a mapping' % i)
        topic = entry.get('topic')
        if not isinstance(topic, str) or not topic.startswith('/'):
            raise RecordingConfigError('streams[%d]: "topic" must be an absolute name, got %r' % (i, topic))
        if topic in seen:
            raise RecordingConfigError('streams[%d]: topic %s listed twice' % (i, topic))
        seen.add(topic)
        rate = entry.get('rate')
        if rate == 'control':
            rate = control_rate
        if isinstance(rate, bool) or not isinstance(rate, (int, float)) or rate < 0 or rate > 1e5:
            raise RecordingConfigError('streams[%d] (%s): "rate" must be a number in [0, 1e5] Hz, got %r'
                                       % (i, topic, rate))
        streams.append(Stream(topic, float(rate), str(entry.get('group', 'other')),
                              bool(entry.get('required', True)), bool(entry.get('header', True)),
                              _stream_in_process(entry, i, topic, manager)))
    return RecordingConfig(streams,
                           float(_number(data, 'min_rate_fraction', 0.8, 0.0, 1.0)),
                           float(_number(data, 'gap_factor', 3.0, 1.0, 100.0)),
                           int(_number(data, 'buffer_mb', 1024, 16, 65536)),
                           int(_number(data, 'chunk_kb', 4096, 64, 1048576)),
                           int(_number(data, 'subscriber_queue', 2000, 100, 1000000)),
                           _flag(data, 'tcp_nodelay', False), manager, part)


def _flag(data, key, default):
    value = data.get(key, default)
    if not isinstance(value, bool):
        raise RecordingConfigError('"%s" must be true or false, got %r' % (key, value))
    return value


def load_recording_config(path, control_rate=1000.0):
    try:
        with open(path) as stream:
            data = yaml.safe_load(stream)
    except (OSError, yaml.YAMLError) as exc:
        raise RecordingConfigError('cannot read %s: %s' % (path, exc))
    try:
        return parse_recording_config(data, control_rate)
    except RecordingConfigError as exc:
        raise RecordingConfigError('%s: %s' % (path, exc))


def recorder_command(config, output, extra_topics=(), in_process=True):
    """argv of saras_bringup's ``bag_recorder`` (rosbag record with a ``subscriber_queue`` deep
    per-topic queue; rosbag record's fixed 100 lost bursts) writing ``output`` (a .bag path): the
    main topics when ``in_process`` (the in-process streams go to the part bag of
    :func:`stream_recorder_command`), every configured topic otherwise."""
    topics = config.main_topics if in_process else config.topics
    return (['rosrun', 'saras_bringup', 'bag_recorder', '-O', output,
             '--buffsize', str(config.buffer_mb), '--chunksize', str(config.chunk_kb),
             '--queue', str(config.queue)] + (['--tcpnodelay'] if config.tcp_nodelay else [])
            + topics + list(extra_topics))


def _stem(output):
    """``/x/platform.bag`` -> ``/x/platform``."""
    return output[:-len('.bag')] if output.endswith('.bag') else output


def part_path(output, part):
    """The part bag ``part`` of the recording whose main bag is ``output``:
    ``/x/platform.bag`` -> ``/x/platform.<part>.bag``."""
    return '%s.%s.bag' % (_stem(output), part)


def stream_recorder_command(config, output, node_name):
    """argv loading the ``saras_bringup/StreamRecorder`` nodelet into ``in_process_manager``: it
    records the in-process topics into ``part_path(output, in_process_part)`` (``output``: the main
    bag). The loader is node ``<node_name>_<part>``; SIGINT to it unloads the nodelet, which closes
    the part bag."""
    if not config.in_process_manager or not config.in_process_topics:
        raise RecordingConfigError('no in_process streams configured')
    part = config.in_process_part
    return ['rosrun', 'nodelet', 'nodelet', 'load', 'saras_bringup/StreamRecorder', config.in_process_manager,
            '__name:=%s_%s' % (node_name.rstrip('/').rsplit('/', 1)[-1], part),
            '_output:=' + os.path.abspath(part_path(output, part)),
            '_topics:=' + ','.join(config.in_process_topics),
            '_buffer_mb:=%d' % config.buffer_mb, '_chunk_kb:=%d' % config.chunk_kb]


def recording_bags(output, config=None):
    """The bags of the recording whose main bag is ``output``: ``[output]`` and its part bags that
    exist. With ``config``, its ``in_process_part``; without, every closed ``<stem>.*.bag`` sibling
    (sorted; a part still open is ``.bag.active`` and not read)."""
    if config is not None:
        parts = [part_path(output, config.in_process_part)] if config.in_process_part else []
    else:
        parts = sorted(glob.glob(glob.escape(_stem(output)) + '.*.bag'))
    return [output] + [p for p in parts if os.path.isfile(p) and p != output]


def _as_list(bag_paths):
    return [bag_paths] if isinstance(bag_paths, str) else list(bag_paths)


@contextlib.contextmanager
def open_bags(bag_paths):
    """``rosbag.Bag`` of each path (one path or a list), closed together."""
    import rosbag  # noqa: delayed so that the pure functions work without ROS
    with contextlib.ExitStack() as stack:
        yield [stack.enter_context(rosbag.Bag(p)) for p in _as_list(bag_paths)]


def read_merged(bags, **kwargs):
    """``read_messages(**kwargs)`` of several open bags as one stream in receive-time order (a topic
    recorded in two bags comes out merged)."""
    streams = [bag.read_messages(**kwargs) for bag in bags]
    return streams[0] if len(streams) == 1 else heapq.merge(*streams, key=lambda m: m[2])


def start_time(bags):
    """Receive time of the first message of several open bags [s]; None when they are all empty."""
    times = []
    for bag in bags:
        try:
            times.append(bag.get_start_time())
        except Exception:  # rosbag.ROSBagException: an empty bag (e.g. a part whose streams never came)
            pass
    return min(times) if times else None


_HEADER = struct.Struct('<III')  # std_msgs/Header starts with uint32 seq, time stamp (secs, nsecs)


class StreamStats(object):
    """What the bag holds for one topic."""

    def __init__(self, topic):
        self.topic = topic
        self.msg_type = ''
        self.count = 0
        self.first = None          # bag receive time of the first / last message [s]
        self.last = None
        self.seq_gaps = 0          # messages missing according to header.seq
        self.stamp_gaps = 0        # intervals longer than gap_factor / rate
        self.max_interval = 0.0    # longest interval between consecutive messages [s]
        self._prev_seq = None
        self._prev_t = None

    @property
    def duration(self):
        return (self.last - self.first) if self.count > 1 else 0.0

    @property
    def rate(self):
        return (self.count - 1) / self.duration if self.duration > 0 else 0.0

    def add(self, t_receive, header):
        """Account one message: receive time [s] and (seq, stamp [s]) or None when headerless."""
        self.count += 1
        if self.first is None:
            self.first = t_receive
        self.last = t_receive
        t = t_receive
        if header is not None:
            seq, stamp = header
            if stamp > 0:
                t = stamp
            if self._prev_seq is not None and seq > self._prev_seq + 1 and self._prev_seq != 0:
                self.seq_gaps += seq - self._prev_seq - 1
            self._prev_seq = seq
        if self._prev_t is not None:
            self.max_interval = max(self.max_interval, t - self._prev_t)
        self._prev_t = t

    def finish(self, nominal_rate, gap_factor, intervals):
        if nominal_rate > 0:
            limit = gap_factor / nominal_rate
            self.stamp_gaps = sum(1 for dt in intervals if dt > limit)


def check_bag(bag_paths, config, topics=None, skews=None):
    """Measure every configured stream in a recording: one bag path or a list (the main bag and its
    parts, :func:`recording_bags`). A topic recorded in several bags is measured over all its
    messages in receive-time order.

    Returns (results, problems): ``results`` is a list of dicts (one per configured stream plus any
    other recorded topic) and ``problems`` a list of human-readable failures for required streams
    (missing, too slow, or with lost messages). With a dict ``skews``, it is filled with one
    ``stamp_skew.SkewSamples`` per topic with header stamps (receive - stamp, publishers).
    """
    from saras_bringup.stamp_skew import SkewSamples

    wanted = {s.topic: s for s in config.streams}
    stats, intervals, last_t = {}, {}, {}
    skews = {} if skews is None else skews
    with open_bags(bag_paths) as bags:
        for bag in bags:
            for topic, tinfo in bag.get_type_and_topic_info().topics.items():
                if topic not in stats:
                    stats[topic] = StreamStats(topic)
                    stats[topic].msg_type = tinfo.msg_type
                    intervals[topic] = []
        for topic, raw, t, conn in read_merged(bags, topics=topics, raw=True, return_connection_header=True):
            stream = wanted.get(topic)
            data = raw[1]
            header = None
            if stream is None or stream.header:
                if len(data) >= _HEADER.size and _has_header(raw[0]):
                    seq, secs, nsecs = _HEADER.unpack_from(data, 0)
                    header = (seq, secs + 1e-9 * nsecs)
            tr = t.to_sec()
            ts = header[1] if header is not None and header[1] > 0 else tr
            if header is not None and header[1] > 0:
                sk = skews.setdefault(topic, SkewSamples())
                sk.add(tr, ts)
                caller = conn.get('callerid', b'?')
                sk.publishers.add(caller.decode() if isinstance(caller, bytes) else caller)
            if topic in last_t:
                intervals[topic].append(ts - last_t[topic])
            last_t[topic] = ts
            stats[topic].add(tr, header)
    for topic, st in stats.items():
        stream = wanted.get(topic)
        st.finish(stream.rate if stream else 0.0, config.gap_factor, intervals[topic])
    return _results(stats, config)


def _results(stats, config):
    """(results, problems) of :func:`check_bag` from the per-topic :class:`StreamStats`."""
    wanted = {s.topic: s for s in config.streams}
    results, problems = [], []
    for stream in config.streams:
        st = stats.get(stream.topic)
        row = {'topic': stream.topic, 'group': stream.group, 'nominal_rate': stream.rate,
               'required': stream.required, 'count': 0, 'rate': 0.0, 'seq_gaps': 0,
               'stamp_gaps': 0, 'max_interval': 0.0, 'type': '', 'ok': False}
        if st is not None and st.count > 0:
            row.update(count=st.count, rate=st.rate, seq_gaps=st.seq_gaps, stamp_gaps=st.stamp_gaps,
                       max_interval=st.max_interval, type=st.msg_type)
        verdict = _verdict(stream, row, config)
        row['ok'] = verdict is None
        row['problem'] = verdict or ''
        if verdict and stream.required:
            problems.append('%s (%s): %s' % (stream.topic, stream.group, verdict))
        results.append(row)
    for topic, st in sorted(stats.items()):
        if topic not in wanted:
            results.append({'topic': topic, 'group': 'extra', 'nominal_rate': 0.0, 'required': False,
                            'count': st.count, 'rate': st.rate, 'seq_gaps': st.seq_gaps,
                            'stamp_gaps': 0, 'max_interval': st.max_interval, 'type': st.msg_type,
                            'ok': True, 'problem': ''})
    return results, problems


_HEADER_TYPES_CACHE = {}


def _has_header(msg_type):
    """True when the ROS message type starts with a std_msgs/Header (looked up once per type)."""
    if msg_type not in _HEADER_TYPES_CACHE:
        try:
            import roslib.message
            cls = roslib.message.get_message_class(msg_type)
            _HEADER_TYPES_CACHE[msg_type] = bool(cls and cls._has_header)
        except Exception:  # unknown type in this environment: judge on receive time only
            _HEADER_TYPES_CACHE[msg_type] = False
    return _HEADER_TYPES_CACHE[msg_type]


def _verdict(stream, row, config):
    if row['count'] == 0:
        return 'not recorded'
    if stream.rate > 0:
        if row['rate'] < config.min_rate_fraction * stream.rate:
            return 'rate %.1f Hz below %.0f %% of nominal %.0f Hz' % (
                row['rate'], 100 * config.min_rate_fraction, stream.rate)
        if row['seq_gaps'] > 0:
            return '%d messages lost (header.seq gaps)' % row['seq_gaps']
    return None


def format_table(results):
    lines = ['%-44s %-22s %8s %9s %9s %6s %6s  %s' % (
        'topic', 'group', 'count', 'rate[Hz]', 'nominal', 'seqgap', 'tgap', 'status')]
    for r in results:
        status = 'ok' if r['ok'] else ('MISSING' if r['count'] == 0 else 'FAIL')
        if not r['required'] and not r['ok']:
            status = 'optional: ' + r['problem']
        elif not r['ok']:
            status += ': ' + r['problem']
        lines.append('%-44s %-22s %8d %9.1f %9s %6d %6d  %s' % (
            r['topic'], r['group'][:22], r['count'], r['rate'],
            ('%.0f' % r['nominal_rate']) if r['nominal_rate'] > 0 else '-',
            r['seq_gaps'], r['stamp_gaps'], status))
    return '\n'.join(lines)

