"""Tests of flexgear.signals: amplitude spectrum scaling, resolution, peaks, lines."""
import numpy as np
import pytest

from flexgear.results.signals import (WINDOWS, Line, amplitude_spectrum, band_rms, db, find_peaks,
                              line_amplitude, planetary_lines, spur_lines)

FS = 5000.0


def sine(f0, a, n=5000, fs=FS, phase=0.3):
    t = np.arange(n) / fs
    return a * np.cos(2 * np.pi * f0 * t + phase)


@pytest.mark.parametrize("window", ["rectangular", "hann", "hamming", "blackman", "flattop"])
def test_on_bin_sinusoid_amplitude(window):
    f, A = amplitude_spectrum(sine(240.0, 3.7) + 12.0, FS, window=window)
    k = int(np.argmax(A))
    assert f[k] == pytest.approx(240.0)
    assert A[k] == pytest.approx(3.7, rel=1e-9)  # periodic windows: exact on a bin
    assert A[0] < 1e-9  # mean removed


def test_rectangular_on_bin_is_a_single_line():
    f, A = amplitude_spectrum(sine(528.0, 2.0), FS, window="rectangular")
    assert A[528] == pytest.approx(2.0, rel=1e-12)
    assert np.max(np.delete(A, 528)) < 1e-9


def test_off_bin_scalloping_bounds():
    x = sine(240.5, 1.0)  # exactly between two bins
    _, A = amplitude_spectrum(x, FS, window="hann")
    assert db(A.max()) == pytest.approx(-1.42, abs=0.01)  # hann scalloping loss
    _, A = amplitude_spectrum(x, FS, window="flattop")
    assert abs(db(A.max())) < 0.02  # flat top: amplitude-accurate anywhere


def test_frequency_resolution_and_zero_padding():
    n = 3000
    f, A = amplitude_spectrum(sine(250.0, 1.0, n=n), FS)
    assert f[1] - f[0] == pytest.approx(FS / n)
    assert f.size == n // 2 + 1 and f[-1] == pytest.approx(FS / 2)
    f2, A2 = amplitude_spectrum(sine(250.0, 1.0, n=n), FS, nfft=4 * n)
    assert f2[1] - f2[0] == pytest.approx(FS / (4 * n))
    assert A2.max() == pytest.approx(1.0, rel=1e-9)  # zero padding keeps the amplitude
    with pytest.raises(ValueError, match="nfft"):
        amplitude_spectrum(np.ones(10), FS, nfft=5)


def test_odd_length_and_nyquist():
    n = 5001
    f, A = amplitude_spectrum(sine(100.0, 1.0, n=n), FS, window="rectangular", nfft=None)
    assert f.size == n // 2 + 1
    # even length: the Nyquist bin is not doubled
    x = np.cos(np.pi * np.arange(1000))  # amplitude 1 at fs/2
    f, A = amplitude_spectrum(x, FS, window="rectangular", detrend=None)
    assert A[-1] == pytest.approx(1.0)


def test_unknown_window_rejected():
    with pytest.raises(ValueError, match="'kaiserish'") as err:
        amplitude_spectrum(np.ones(16), FS, window="kaiserish")
    for name in WINDOWS:
        assert name in str(err.value)
    with pytest.raises(ValueError, match="detrend"):
        amplitude_spectrum(np.ones(16), FS, detrend="quadratic")
    with pytest.raises(ValueError, match="fs"):
        amplitude_spectrum(np.ones(16), 0.0)


def test_window_aliases_and_array():
    x = sine(240.0, 1.0)
    _, A1 = amplitude_spectrum(x, FS, window="Hann")
    _, A2 = amplitude_spectrum(x, FS, window=np.hanning(5001)[:-1])
    np.testing.assert_allclose(A1, A2, atol=1e-12)
    _, A3 = amplitude_spectrum(x, FS, window="boxcar")
    assert A3.max() == pytest.approx(1.0)


def test_multichannel():
    x = np.stack([sine(240.0, 1.0), sine(480.0, 2.0)])
    f, A = amplitude_spectrum(x, FS)
    assert A.shape == (2, f.size)
    assert A[1, 480] == pytest.approx(2.0)


def test_am_signal_sidebands_and_peaks():
    # planetary-like: carrier 528 Hz, amplitude modulated at 8 Hz with index m
    a0, m, n = 100.0, 0.6, 5000
    t = np.arange(n) / FS
    x = a0 * (1 + m * np.cos(2 * np.pi * 8.0 * t)) * np.cos(2 * np.pi * 528.0 * t)
    f, A = amplitude_spectrum(x, FS, window="hann")
    peaks = find_peaks(f, A, 3, fmin=1.0, min_separation_hz=4.0)
    assert [p.freq for p in peaks] == [528.0, 520.0, 536.0] or \
        [p.freq for p in peaks] == [528.0, 536.0, 520.0]
    assert peaks[0].amplitude == pytest.approx(a0, rel=1e-9)
    for p in peaks[1:]:
        assert p.amplitude == pytest.approx(a0 * m / 2, rel=1e-9)
    assert line_amplitude(f, A, 520.0, 1.0) == pytest.approx(30.0, rel=1e-9)
    assert line_amplitude(f, A, 536.4) == pytest.approx(30.0, rel=1e-9)  # default tol = 1 bin
    # the hann window spreads each line over 3 bins; the separation keeps one peak per line
    peaks = find_peaks(f, A, 10, fmin=1.0, min_separation_hz=4.0)
    assert len(peaks) == 3
    assert peaks == sorted(peaks, key=lambda p: -p.amplitude)
    # band limits
    assert find_peaks(f, A, 5, fmin=530.0) [0].freq == 536.0
    assert find_peaks(f, A, 5, fmax=525.0)[0].freq == 520.0
    assert find_peaks(f, A, 5, fmin=1.0, min_amplitude=50.0) == [(528.0, pytest.approx(100.0))]


def test_find_peaks_separation_keeps_larger():
    f = np.arange(0.0, 100.0, 1.0)
    A = np.zeros_like(f)
    A[[20, 23, 60]] = [1.0, 2.0, 0.5]
    assert [p.freq for p in find_peaks(f, A, 5)] == [23.0, 20.0, 60.0]
    assert [p.freq for p in find_peaks(f, A, 5, min_separation_hz=5.0)] == [23.0, 60.0]


def test_line_amplitude_no_bin():
    f = np.arange(0.0, 10.0, 1.0)
    with pytest.raises(ValueError, match="no frequency bin"):
        line_amplitude(f, np.ones_like(f), 50.0, 0.5)


def test_db():
    assert db(1.0) == 0.0
    assert db(10.0, ref=1.0) == pytest.approx(20.0)
    assert db(0.1, ref=10.0) == pytest.approx(-40.0)
    assert np.isfinite(db(0.0))
    np.testing.assert_allclose(db(np.array([1.0, 100.0])), [0.0, 40.0])
    with pytest.raises(ValueError, match="ref"):
        db(1.0, ref=0.0)


def test_band_rms():
    x = sine(240.0, 2.0) + sine(480.0, 1.0) + 5.0
    assert band_rms(x, FS, 0.0, FS / 2) == pytest.approx(np.std(x), rel=1e-12)
    assert band_rms(x, FS, 200.0, 300.0) == pytest.approx(2.0 / np.sqrt(2), rel=1e-9)
    assert band_rms(x, FS, 400.0, 500.0) == pytest.approx(1.0 / np.sqrt(2), rel=1e-9)


def test_planetary_lines():
    lines = planetary_lines(8.0, 528.0, n_harmonics=3, n_sidebands=3)
    assert all(isinstance(ln, Line) for ln in lines)
    by_label = {ln.label: ln for ln in lines}
    assert by_label["f_a"] == Line(8.0, "f_a", "carrier")
    assert by_label["f_m"] == Line(528.0, "f_m", "mesh")
    assert by_label["3f_m"].freq == 1584.0
    assert by_label["f_m-f_a"] == Line(520.0, "f_m-f_a", "sideband")
    assert by_label["f_m+f_a"].freq == 536.0
    assert by_label["2f_m-2f_a"].freq == 1040.0
    assert by_label["3f_m+3f_a"].freq == 1608.0
    assert len(lines) == 1 + 3 * (1 + 2 * 3)
    assert [ln.freq for ln in lines] == sorted(ln.freq for ln in lines)
    assert {ln.kind for ln in lines} == {"carrier", "mesh", "sideband"}


def test_spur_lines():
    lines = spur_lines(240.0)
    assert [(ln.freq, ln.label, ln.kind) for ln in lines] == [
        (240.0, "f_m", "mesh"), (480.0, "2f_m", "mesh"), (720.0, "3f_m", "mesh"),
        (960.0, "4f_m", "mesh")]
    with pytest.raises(ValueError, match="f_mesh"):
        spur_lines(0.0)
