"""Measurement noise at the sensors: what an accelerometer and its amplifier add to the signal.

A ``[[sensors]]`` entry with ``noise_rms`` or ``snr_db`` records its signals with white
Gaussian noise added, independent from sample to sample at the output rate (flat up to the
Nyquist frequency). ``noise_rms`` is an absolute level in the sensor's quantity (the sensor's
noise floor, the same for every case of a batch) and is added to the signals in that quantity;
``snr_db`` sets the noise of each signal from its own RMS about its mean over the record,
sigma = rms / 10^(snr/20) (also the planet-pass force). The noise is drawn from a seed: the
sensor's ``noise_seed``, else one derived from the whole resolved configuration and the
sensor's name, so that a rerun draws the same noise and every other case, and every sensor,
its own. The noise-free signal is kept beside the measured one (:data:`NOISE_FREE`).
"""
from __future__ import annotations

import hashlib
import zlib

import numpy as np

#: suffix of the noise-free copy of a noisy sensor signal (``/sensors/<name>/<path model>_noise_free``)
NOISE_FREE = "_noise_free"


def derived_seed(config_text: str, sensor: str) -> int:
    """A seed (0 <= seed < 2^63) from the SHA-256 of the resolved configuration ``config_text``
    and the sensor's name."""
    digest = hashlib.sha256(f"{config_text}\n[sensor {sensor}]".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


def noise_sigma(sensor, y: np.ndarray, units: str) -> float | None:
    """The noise RMS of ``sensor`` on its signal ``y`` in ``units``: ``noise_rms`` on a signal in
    the sensor's own units, rms(y - mean y) 10^(-snr_db/20) with ``snr_db``; None: no noise on
    this signal."""
    if sensor.snr_db is not None:
        return float(np.std(y)) * 10.0 ** (-sensor.snr_db / 20.0)
    if sensor.noise_rms is not None and units == sensor.units:
        return float(sensor.noise_rms)
    return None


def add_noise(signals: dict, sensors, config_text: str) -> None:
    """Add each noisy sensor's measurement noise to its :class:`~flexgear.results.store.SensorSignals`
    in ``signals`` (name -> SensorSignals) in place: the measured signal at the path model's name,
    the noise-free one at ``<name>_noise_free``, the noise's RMS, SNR and seed in the measured
    signal's attributes. Each signal draws its own stream (the seed and the path model's name)."""
    for sensor in sensors:
        if not sensor.noisy:
            continue
        s = signals[sensor.name]
        seed = sensor.noise_seed if sensor.noise_seed is not None else derived_seed(config_text, sensor.name)
        for path in list(s.signals):
            y = np.asarray(s.signals[path], dtype=float)
            sigma = noise_sigma(sensor, y, s.signal_attrs[path]["units"])
            if sigma is None:
                continue
            rng = np.random.default_rng(np.random.SeedSequence([seed, zlib.crc32(path.encode())]))
            s.signals[path + NOISE_FREE] = y
            clean = s.signal_attrs[path]
            s.signal_attrs[path + NOISE_FREE] = dict(clean, description=clean["description"] + ", without the "
                                                     "measurement noise")
            s.signals[path] = y + sigma * rng.standard_normal(y.shape)
            attrs = s.signal_attrs[path]
            attrs["description"] += f", with white Gaussian measurement noise (rms {sigma:.4g} {attrs['units']})"
            attrs.update(noise_rms=sigma, noise_seed=int(seed))
            if sensor.snr_db is not None:
                attrs["snr_db"] = float(sensor.snr_db)
