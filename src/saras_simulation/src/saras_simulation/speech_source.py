"""Synthetic operating-room voice for the simulated microphone, ROS-free.

:class:`SpeechLikeSource`: deterministic speech-like signal: syllables (voiced harmonic series with
a jittered pitch of about ``f0`` Hz, shaped by vowel formants, 20 ms raised-cosine attack/release)
separated by short and long pauses, over low-level room noise. Chunk-size independent: generating
N samples in one call or in many calls gives the same samples. Samples are signed 16-bit (S16LE),
mono unless ``channels`` > 1 (then every channel carries the same signal).
"""
import math

import numpy as np

#: Vowel formants (F1, F2, F3) [Hz] used for the syllables.
VOWELS = ((730, 1090, 2440), (270, 2290, 3010), (530, 1840, 2480), (570, 840, 2410),
          (300, 870, 2240), (660, 1720, 2410))


class SpeechLikeSource(object):
    """Synthetic speech-like PCM generator.

    Parameters: ``sample_rate`` [Hz], ``f0`` mean pitch [Hz], ``level`` peak amplitude of speech
    (fraction of int16 full scale), ``noise_level`` room-noise RMS (fraction of full scale),
    ``seed`` for reproducibility.
    """

    name = 'synthetic'

    def __init__(self, sample_rate=16000, f0=130.0, level=0.3, noise_level=0.003, seed=1,
                 channels=1):
        if not (8000 <= sample_rate <= 192000 and 50.0 <= f0 <= 400.0 and 0 < level <= 1.0
                and 0 <= noise_level < 0.5 and channels >= 1):
            raise ValueError('audio: invalid synthetic source parameters')
        self.fs = int(sample_rate)
        self.f0 = float(f0)
        self.level = float(level)
        self.noise = float(noise_level)
        self.channels = int(channels)
        self._rng = np.random.default_rng(seed)
        self._noise_rng = np.random.default_rng(seed + 1000)
        self._phase = 0.0           # fundamental phase [rad]
        self._seg_left = 0          # samples left in the current segment
        self._seg_len = 1
        self._voiced = False
        self._formants = VOWELS[0]
        self._pitch = self.f0
        self._syllables_to_pause = 3
        self.samples_generated = 0
        self._harmonic_cache = (None, None)

    def _next_segment(self):
        r = self._rng
        if self._voiced:
            self._voiced = False
            self._syllables_to_pause -= 1
            if self._syllables_to_pause <= 0:
                dur = r.uniform(0.4, 1.0)         # pause between phrases
                self._syllables_to_pause = int(r.integers(2, 7))
            else:
                dur = r.uniform(0.04, 0.12)       # gap between syllables
        else:
            self._voiced = True
            dur = r.uniform(0.12, 0.30)
            self._formants = VOWELS[int(r.integers(len(VOWELS)))]
            self._pitch = self.f0 * r.uniform(0.85, 1.2)
        self._seg_len = max(1, int(dur * self.fs))
        self._seg_left = self._seg_len

    def _voiced_block(self, n, pos):
        """n samples of the current syllable starting at offset ``pos`` within it."""
        k = np.arange(n)
        idx = pos + k
        tt = idx / float(self.fs)
        f = self._pitch * (1.0 + 0.05 * np.sin(2 * math.pi * 5.0 * tt) - 0.15 * idx / self._seg_len)
        phase = self._phase + np.cumsum(2 * math.pi * f / self.fs)
        self._phase = float(phase[-1] % (2 * math.pi))
        hs, amps, roots = self._harmonics()
        # all harmonics at once, then summed in harmonic order (the same sums as one at a time)
        out = (amps * np.sin(hs * phase) / roots).sum(axis=0)
        ramp = int(0.02 * self.fs)
        env = np.minimum(1.0, np.minimum((idx + 1) / ramp, (self._seg_len - idx) / ramp))
        env = 0.5 - 0.5 * np.cos(math.pi * np.clip(env, 0.0, 1.0))
        return out * env

    def _harmonics(self):
        """Harmonic numbers, formant-shaped amplitudes and sqrt(h) of the current syllable, as
        (H, 1) columns; computed once per syllable (they depend on its pitch and vowel only)."""
        key = (self._pitch, self._formants)
        if self._harmonic_cache[0] != key:
            hs = list(range(1, int(3800 // self._pitch) + 1))
            amps = [sum(math.exp(-0.5 * ((h * self._pitch - F) / (60.0 + 0.08 * F)) ** 2) / (1 + i)
                        for i, F in enumerate(self._formants)) + 0.02 for h in hs]
            col = lambda v: np.array(v, dtype=float).reshape(-1, 1)
            self._harmonic_cache = (key, (col(hs), col(amps), col([math.sqrt(h) for h in hs])))
        return self._harmonic_cache[1]

    def read(self, frames):
        """Next ``frames`` frames as int16 array of length frames * channels (interleaved)."""
        out = np.zeros(frames)
        i = 0
        while i < frames:
            if self._seg_left <= 0:
                self._next_segment()
            n = min(frames - i, self._seg_left)
            if self._voiced:
                out[i:i + n] = self._voiced_block(n, self._seg_len - self._seg_left)
            self._seg_left -= n
            i += n
        peak_norm = 1.6  # typical peak of the harmonic sum above, keeps speech below level
        sig = self.level * out / peak_norm + self.noise * self._noise_rng.standard_normal(frames)
        pcm = np.clip(np.round(sig * 32767.0), -32768, 32767).astype(np.int16)
        self.samples_generated += frames
        if self.channels > 1:
            pcm = np.repeat(pcm, self.channels)
        return pcm

    def close(self):
        pass
