"""Core tests of saras_simulation.speech_source (no roscore)."""
import numpy as np
import pytest

from saras_simulation import speech_source as au

FS = 16000


def frames_rms(x, n=320):
    x = x[: len(x) // n * n].astype(float).reshape(-1, n)
    return np.sqrt((x ** 2).mean(axis=1))


def test_chunking_does_not_change_the_signal():
    a = au.SpeechLikeSource(FS, seed=4).read(FS * 3)
    src = au.SpeechLikeSource(FS, seed=4)
    b = np.concatenate([src.read(n) for n in [320] * 100 + [7, 313, 15680]])
    assert a.dtype == np.int16 and np.array_equal(a, b)


def test_speech_like_structure():
    x = au.SpeechLikeSource(FS, f0=130.0, level=0.3, seed=2).read(FS * 10)
    assert np.abs(x).max() <= 0.3 * 32767 * 1.05
    rms = frames_rms(x)
    silent = rms < 0.01 * 32767
    # pauses and syllables both present, like speech
    assert 0.15 < silent.mean() < 0.7
    # syllabic rate: voiced onsets per second in 1.5..7
    onsets = np.count_nonzero(~silent[1:] & silent[:-1])
    assert 15 <= onsets <= 70
    # pitch of the loudest frames from the autocorrelation peak in 60..400 Hz
    pitches = []
    for i in np.argsort(rms)[-30:]:
        seg = x[i * 320:(i + 1) * 320 + 320].astype(float)
        seg -= seg.mean()
        ac = np.correlate(seg, seg, 'full')[len(seg) - 1:]
        lo, hi = FS // 400, FS // 60
        pitches.append(FS / (lo + np.argmax(ac[lo:hi])))
    assert 130 * 0.7 < np.median(pitches) < 130 * 1.3


def test_noise_floor_and_validation():
    x = au.SpeechLikeSource(FS, noise_level=0.003, seed=9).read(FS * 4)
    rms = frames_rms(x)
    floor = np.median(np.sort(rms)[:20])
    assert 0.5 * 0.003 * 32767 < floor < 2.0 * 0.003 * 32767
    with pytest.raises(ValueError):
        au.SpeechLikeSource(100)
    stereo = au.SpeechLikeSource(FS, channels=2).read(10)
    assert len(stereo) == 20 and np.array_equal(stereo[0::2], stereo[1::2])
