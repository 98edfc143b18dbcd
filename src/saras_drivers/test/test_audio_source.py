"""Core tests of saras_drivers.audio_source (no roscore, no sound card needed)."""
import os
import stat

import numpy as np
import pytest

from saras_drivers import audio_source as au


def fake_arecord(tmp_path, listing, payload=b''):
    """A stand-in `arecord` on PATH: `-l` prints listing, otherwise writes payload."""
    exe = tmp_path / 'arecord'
    data = tmp_path / 'payload.raw'
    data.write_bytes(payload)
    exe.write_text('#!/bin/sh\nif [ "$1" = "-l" ]; then printf "%s\\n" "' + listing + '"; exit 0; fi\n'
                   'cat "' + str(data) + '"\n')
    exe.chmod(exe.stat().st_mode | stat.S_IEXEC)
    return str(tmp_path)


def test_no_alsa_without_arecord(monkeypatch, tmp_path):
    monkeypatch.setenv('PATH', str(tmp_path))   # no arecord anywhere
    ok, why = au.alsa_available()
    assert not ok and 'not installed' in why


def test_chunk_format_is_validated():
    assert au.chunk_frames(16000, 1, 20) == 320
    for args, name in (((100, 1, 20), '~sample_rate'), ((16000, 0, 20), '~channels'),
                       ((16000, 1, 0.01), '~chunk_ms'), ((44100, 1, 0.5), '~chunk_ms')):
        with pytest.raises(ValueError, match=name):
            au.chunk_frames(*args)


def test_alsa_detection_and_capture_through_arecord(monkeypatch, tmp_path):
    samples = (np.arange(640) - 320).astype('<i2')
    path = fake_arecord(tmp_path, 'card 0: PCH [HDA Intel], device 0: ALC', samples.tobytes())
    monkeypatch.setenv('PATH', path + os.pathsep + '/bin:/usr/bin')
    ok, _ = au.alsa_available()
    assert ok
    src = au.AlsaCapture()
    try:
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
