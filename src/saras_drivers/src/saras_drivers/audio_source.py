"""Operating-room microphone capture (D7.2 Section 2.1 recording list), ROS-free.

* :func:`alsa_available`: ``arecord`` (alsa-utils) on PATH and a capture card listed.
* :class:`AlsaCapture`: ALSA capture through ``arecord`` in a child process (no Python ALSA binding).
* :func:`chunk_frames`: validated audio format -> frames per chunk.

Samples are signed 16-bit little-endian (S16LE), interleaved when ``channels`` > 1.
"""
import shutil
import subprocess

import numpy as np


def chunk_frames(sample_rate, channels, chunk_ms):
    """Frames per chunk of ``chunk_ms`` ms; ValueError naming the parameter when out of range."""
    if not 8000 <= sample_rate <= 192000:
        raise ValueError('parameter ~sample_rate must be in [8000, 192000] Hz, got %s' % sample_rate)
    if not 1 <= channels <= 8:
        raise ValueError('parameter ~channels must be in [1, 8], got %s' % channels)
    frames = int(round(sample_rate * chunk_ms / 1000.0))
    if not (1.0 <= chunk_ms <= 1000.0) or frames * 1000.0 != sample_rate * chunk_ms:
        raise ValueError('parameter ~chunk_ms must be in [1, 1000] ms and give whole samples, got %s'
                         % chunk_ms)
    return frames


def alsa_available(device='default'):
    """(available, reason): ``arecord`` on PATH and at least one capture card listed."""
    exe = shutil.which('arecord')
    if exe is None:
        return False, 'arecord (alsa-utils) not installed'
    try:
        out = subprocess.run([exe, '-l'], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                             timeout=3.0, check=False).stdout.decode('utf-8', 'replace')
    except (OSError, subprocess.SubprocessError) as ex:
        return False, 'arecord -l failed: %s' % ex
    if 'card ' not in out:
        return False, 'no ALSA capture device'
    return True, 'ALSA device %s' % device


class AlsaCapture(object):
    """Blocking S16LE capture from ALSA via ``arecord`` (no Python ALSA binding needed)."""

    def __init__(self, device='default', sample_rate=16000, channels=1):
        self.name = device
        self.fs = int(sample_rate)
        self.channels = int(channels)
        self.proc = subprocess.Popen(
            ['arecord', '-q', '-D', device, '-f', 'S16_LE', '-r', str(self.fs),
             '-c', str(self.channels), '-t', 'raw'],
            stdout=subprocess.PIPE, stderr=subprocess.PIPE)

    def read(self, frames):
        """Blocks until ``frames`` frames are captured; raises IOError when capture stops."""
        want = frames * self.channels * 2
        buf = b''
        while len(buf) < want:
            chunk = self.proc.stdout.read(want - len(buf))
            if not chunk:
                err = self.proc.stderr.read().decode('utf-8', 'replace').strip()
                raise IOError('ALSA capture stopped: %s' % (err or 'end of stream'))
            buf += chunk
        return np.frombuffer(buf, dtype='<i2').astype(np.int16)

    def close(self):
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=2.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
