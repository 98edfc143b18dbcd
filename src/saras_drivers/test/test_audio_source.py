"""Core tests of saras_drivers.audio_source (no roscore, no sound card needed)."""
import os
import stat

import numpy as np
import pytest

from saras_drivers import audio_source as au

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


def fake_arecord(tmp_path, listing, payload=b''):
    """A stand-in `arecord` on PATH: `-l` prints listing, otherwise writes payload."""
    exe = tmp_path / 'arecord'
    data = tmp_path / 'payload.raw'
    data.write_bytes(payload)
    exe.write_text('#!/bin/sh\nif [ "$1" = "-l" ]; then printf "%s\\n" "' + listing + '"; exit 0; fi\n'
                   'cat "' + str(data) + '"\n')
    exe.chmod(exe.stat().st_mode | stat.S_IEXEC)
    return str(tmp_path)


def test_fallback_to_synthetic_without_alsa(monkeypatch, tmp_path):
    monkeypatch.setenv('PATH', str(tmp_path))   # no arecord anywhere
    src, why = au.open_source('auto')
    assert isinstance(src, au.SpeechLikeSource) and 'not installed' in why
    with pytest.raises(ValueError, match='source=alsa'):
        au.open_source('alsa')
    with pytest.raises(ValueError, match='parameter source'):
        au.open_source('pulse')


def test_alsa_detection_and_capture_through_arecord(monkeypatch, tmp_path):
    samples = (np.arange(640) - 320).astype('<i2')
    path = fake_arecord(tmp_path, 'card 0: PCH [HDA Intel], device 0: ALC', samples.tobytes())
    monkeypatch.setenv('PATH', path + os.pathsep + '/bin:/usr/bin')
    ok, _ = au.alsa_available()
    assert ok
    src, why = au.open_source('auto')
    try:
        assert isinstance(src, au.AlsaCapture)
        assert np.array_equal(src.read(320), samples[:320])
        assert np.array_equal(src.read(320), samples[320:])
        with pytest.raises(IOError):
            src.read(320)                          # capture ended: clear error, no hang
    finally:
        src.close()
    nocard = tmp_path / 'nocard'
    nocard.mkdir()
    monkeypatch.setenv('PATH', fake_arecord(nocard, '') + os.pathsep + '/bin:/usr/bin')
    assert au.alsa_available() == (False, 'no ALSA capture device')
