"""Measurement noise at the sensors: what an accelerometer and its amplifier add to the signal.

A ``[[sensors]]`` entry with ``noise_rms`` or ``snr_db`` records its signals with white
Gaussian noise added, independent from sample to sample at the output rate (flat up to the
Nyquist frequency). ``noise_rms`` is an absolute level in the sensor's quantity (the sensor's
noise floor, the same for every case of a batch) and is added to the signals in that quantity;
``snr_db`` sets the noise of each signal from its own RMS about its mean over the record,
sigma = rms / 10^(snr/20) (also the planet-pass force). The noise is drawn from the sensor's
``noise_seed`` (else a seed derived from the whole resolved configuration and the sensor's
name) together with the case, the configuration without the seeds (:func:`case_key`): a
rerun draws the same noise; seed 1 of two cases, two sensors or two signals are independent
draws, and so are the seeds of one case (repeated measurements). The noise-free signal is kept
beside the measured one (:data:`NOISE_FREE`); :func:`remeasure` draws another measurement from
it without simulating again.
"""
from __future__ import annotations

import copy
import dataclasses
import hashlib
import tomllib
import zlib

import numpy as np
import tomli_w

#: suffix of the noise-free copy of a noisy sensor signal (``/sensors/<name>/<path model>_noise_free``)
NOISE_FREE = "_noise_free"
#: what the noise-free copy's description adds to the signal's
WITHOUT_NOISE = ", without the measurement noise"


def measured(names) -> list[str]:
    """The measured signals among a sensor's signal ``names``: not the noise-free copies."""
    return [n for n in names if not n.endswith(NOISE_FREE)]


def derived_seed(config_text: str, sensor: str) -> int:
    """A seed (0 <= seed < 2^63) from the SHA-256 of the resolved configuration ``config_text``
    and the sensor's name."""
    digest = hashlib.sha256(f"{config_text}\n[sensor {sensor}]".encode()).digest()
    return int.from_bytes(digest[:8], "little") >> 1


def case_key(config_text: str) -> int:
    """The case a noise stream belongs to (0 <= key < 2^63): the SHA-256 of the resolved
    configuration ``config_text`` without the sensors' ``noise_seed``, so that the seeds of a
    case are its repeated measurements and one seed in two cases two independent draws."""
    doc = tomllib.loads(config_text)
    for sensor in doc.get("sensors", []):
        sensor.pop("noise_seed", None)
    return int.from_bytes(hashlib.sha256(tomli_w.dumps(doc).encode()).digest()[:8], "little") >> 1


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
    signal's attributes. Each signal draws its own stream (the seed, the case and the path
    model's name, and the sensor's)."""
    key = case_key(config_text) if any(sensor.noisy for sensor in sensors) else 0
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
            # the sensor's name and the signal's in the stream: one seed on two sensors, two draws
            entropy = [seed, key, zlib.crc32(sensor.name.encode()), zlib.crc32(path.encode())]
            rng = np.random.default_rng(np.random.SeedSequence(entropy))
            s.signals[path + NOISE_FREE] = y
            clean = s.signal_attrs[path]
            s.signal_attrs[path + NOISE_FREE] = dict(clean, description=clean["description"] + WITHOUT_NOISE)
            s.signals[path] = y + sigma * rng.standard_normal(y.shape)
            attrs = s.signal_attrs[path]
            attrs["description"] += f", with white Gaussian measurement noise (rms {sigma:.4g} {attrs['units']})"
            attrs.update(noise_rms=sigma, noise_seed=int(seed))
            if sensor.snr_db is not None:
                attrs["snr_db"] = float(sensor.snr_db)


def remeasure(result, seed: int):
    """Another measurement of ``result`` (a :class:`~flexgear.results.store.Result` with noisy
    sensors): a copy whose noisy sensor signals are drawn again with ``noise_seed = seed`` on every
    noisy sensor, equal to the run of its configuration with that seed, without simulating again
    (the noise-free signals are kept beside the measured ones). The copy's ``config_toml``
    records the seed."""
    from ..config import loads_config

    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or not 0 <= seed < 2 ** 63:
        raise ValueError(f"remeasure(seed={seed!r}): must be an integer in [0, 2^63)")
    cfg = loads_config(result.config_toml)
    noisy = [dataclasses.replace(s, noise_seed=int(seed)) for s in cfg.sensors if s.noisy]
    if not noisy:
        raise ValueError("remeasure: the result has no sensor with measurement noise (noise_rms or snr_db)")
    doc = tomllib.loads(result.config_toml)
    for entry in doc.get("sensors", []):
        if any(entry.get("name") == s.name for s in noisy):
            entry["noise_seed"] = int(seed)
    text = tomli_w.dumps(doc)
    sensors = copy.deepcopy(result.sensors)
    for sensor in noisy:
        sig = sensors[sensor.name]
        sig.attrs = sensor.definition()  # its noise_seed
        clean = [p for p in sig.signals if p + NOISE_FREE in sig.signals]
        for p in clean:  # back to the noise-free signal and its attributes
            sig.signals[p] = sig.signals.pop(p + NOISE_FREE)
            attrs = sig.signal_attrs.pop(p + NOISE_FREE)
            sig.signal_attrs[p] = dict(attrs, description=attrs["description"].removesuffix(WITHOUT_NOISE))
    add_noise(sensors, noisy, text)
    return dataclasses.replace(result, sensors=sensors, config_toml=text)
