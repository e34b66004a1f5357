"""Synthetic result files in the ``results.h5`` layout for the monitoring tests: a planetary set with
exact kinematics (MERCURY 1-A's tooth counts) and a housing sensor that hears each planet only
while it passes, with a known vibration per planet."""
from __future__ import annotations

import h5py
import numpy as np

Z_SUN, Z_PLANET, Z_RING, PLANETS = 24, 21, 66, 3
F_CARRIER = 8.0  # Hz
R_CARRIER = 0.045  # m
SENSOR_DEG = 90.0
PLANET_OFFSETS = (0.0, 0.3, 0.7)  # planet spin phase on assembly [rad], arbitrary


def planet_vibration(j: int, phi, fault: float = 0.0, background: float = 0.05):
    """The vibration of planet j+1 against its angle in the carrier ``phi`` [rad]: the mesh order
    z_p, amplitude-modulated at order j+1 (so every tooth differs and every planet differs), a
    ``background`` line at order 7 (in the difference signal), and with ``fault`` a bump of that
    height on the tooth at phi = 1 rad (planet 1 only)."""
    x = (1.0 + 0.4 * np.cos((j + 1) * phi + j)) * np.cos(Z_PLANET * phi) + background * np.cos(7 * phi + j)
    if fault and j == 0:
        d = (phi - 1.0 + np.pi) % (2 * np.pi) - np.pi
        x = x + fault * np.exp(-0.5 * (d / (0.3 * 2 * np.pi / Z_PLANET)) ** 2)
    return x


def path_gain(offset):
    """Transfer from a planet to the sensor against the planet's angular distance from it [rad of
    carrier angle]: 1 within 3.5 tooth-meshing periods, a cosine taper to 0 at 6 (smooth, so the
    resampling sees no step)."""
    pitch = 2 * np.pi / Z_RING
    a = np.abs(offset) / pitch
    return np.where(a <= 3.5, 1.0, np.where(a >= 6.0, 0.0, 0.5 * (1 + np.cos(np.pi * (a - 3.5) / 2.5))))


def planet_angles(t):
    """Carrier angle, and each planet's position on the carrier and angle relative to it [rad]."""
    carrier = 2 * np.pi * F_CARRIER * t
    beta = [np.pi / 2 + 2 * np.pi * j / PLANETS for j in range(PLANETS)]
    rel = [-(Z_RING / Z_PLANET) * carrier + PLANET_OFFSETS[j] for j in range(PLANETS)]
    return carrier, beta, rel


def sun_vibration(m, fault: float):
    """The sun's mesh vibration against the sun's material angle ``m`` [rad] where it meets a
    planet: the mesh order z_s and, with ``fault``, a bump of that height on the tooth at m = 1."""
    d = (m - 1.0 + np.pi) % (2 * np.pi) - np.pi
    return np.cos(Z_SUN * m) + fault * np.exp(-0.5 * (d / (0.3 * 2 * np.pi / Z_SUN)) ** 2)


def write_planetary(path, duration: float = 1.0, fs: float = 10000.0, fault: float = 0.0,
                    background: float = 0.05, sun_fault: float | None = None, pass_load: float = 0.0) -> None:
    """A planetary result file with ``/sensors/top/acceleration`` heard at 90 degrees. With
    ``sun_fault`` the sun's meshes too (:func:`sun_vibration`): with planet j, the sun meets it
    at the material angle psi_j - (sun - carrier), heard through that planet's path; with
    ``pass_load`` each planet's steady load of that size too, a bump as it passes (content that
    repeats with the carrier, as a housing sensor's planet passes)."""
    t = np.arange(int(round(duration * fs))) / fs
    carrier, beta, rel = planet_angles(t)
    wrap = lambda a: (a + np.pi) % (2 * np.pi) - np.pi  # noqa: E731
    alpha = np.radians(SENSOR_DEG)
    x = sum(path_gain(wrap(carrier + beta[j] - alpha)) * planet_vibration(j, rel[j], fault, background)
            for j in range(PLANETS))
    x = x + sum(pass_load * path_gain(wrap(carrier + beta[j] - alpha)) for j in range(PLANETS))
    if sun_fault is not None:
        sun_rel = carrier * Z_RING / Z_SUN
        x = x + sum(path_gain(wrap(carrier + beta[j] - alpha)) * sun_vibration(beta[j] - sun_rel, sun_fault)
                    for j in range(PLANETS))
    zeros2 = np.zeros((t.size, 2))
    with h5py.File(path, "w") as h5:
        h5.attrs["passband_hz"] = 0.4 * fs
        h5["time"] = t
        h5["sensors/top/acceleration"] = x
        h5["sensors/top/acceleration"].attrs["units"] = "m/s^2"

        def body(name, angle, z, centre=zeros2):
            g = h5.create_group(f"bodies/{name}")
            g["angle"] = angle
            g["position"] = centre
            g.attrs["z"] = z

        body("sun", carrier * (1 + Z_RING / Z_SUN), Z_SUN)
        body("carrier", carrier, 0)
        body("ring", np.zeros_like(t), Z_RING)
        for j in range(PLANETS):
            pos = R_CARRIER * np.column_stack([np.cos(carrier + beta[j]), np.sin(carrier + beta[j])])
            body(f"planet{j + 1}", carrier + rel[j], Z_PLANET, pos)
