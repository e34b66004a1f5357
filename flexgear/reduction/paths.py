"""Simplified transfer paths from the gears to a sensor, applied one way to recorded forces.

For rigid and lumped runs, without the housing in the multi-body model:

* :class:`TransferPath`: the reduced housing on its feet (:mod:`flexgear.reduction.housing`)
  loaded at its seats and by the ring, whose bolts are tied to it as one rigid body
  (:func:`ring_tie`); **no feedback** (the forces are those of a run on a rigid housing).
  Linear, modal damping ratio zeta::

      H(omega) = (i omega)^p  C Phi diag(1 / (omega_s^2 - omega^2 + 2 i zeta omega_s omega)) Phi^T B

  (p = 0, 1, 2 for displacement, velocity, acceleration; C the sensors' recovery rows, B the
  input channels' generalised forces, Phi all mass-normalised modes of ``(K + K_ground, M)``
  in the tied coordinates),
  evaluated as ``H(f_k) F_k`` on an FFT grid padded by the impulse response's decay time (to
  1e-12), so the circular convolution equals the linear one.
* :func:`planet_pass_signal`: McFadden and Smith's (1985) planet-pass window: each planet's
  meshing vibration weighted by a window of its angular distance from the sensor, summed over
  the planets.
"""
from __future__ import annotations

import math

import numpy as np
import scipy.linalg as sla
from scipy import fft as sfft

from ..errors import ConfigError
from ..fe.elasticity import single_threaded_blas
from ..gears.housing import QUANTITY_ORDER, WINDOWS
from .recovery import rigid_row

#: the padding makes the impulse response decay to this fraction before it wraps around
DECAY = 1e-12


def housing_inputs(red, ring_centre=(0.0, 0.0)) -> dict:
    """Input channels of a reduced housing: name -> generalised-force column (n,) of a unit
    load [N or N m] that the gear set puts on the housing.

    ``<shaft>.x``, ``<shaft>.y`` for the shafts its seats carry (a force at the seat's centre:
    the bearing's reaction on the housing); with ring bolts, ``ring.x``, ``ring.y``,
    ``ring.moment`` (force and moment of the ring on the housing about ``ring_centre``), shared
    out over the bolts as ``E (E^T E)^-1`` (``E`` = :meth:`~flexgear.reduction.housing.HousingReduction.ring_coupling`): the least-norm
    share whose resultant is the ring's load, and, on bolts tied to a rigid ring
    (:class:`TransferPath`), exactly the ring's load on its coordinates."""
    out = {}
    for p in red.role("seat"):
        B = red.force_at(p)
        for shaft in p.shafts:
            out[f"{shaft}.x"], out[f"{shaft}.y"] = B[:, 0], B[:, 1]
    if red.role("bolt"):
        E = red.ring_coupling(ring_centre)
        S = E @ np.linalg.inv(E.T @ E)
        out["ring.x"], out["ring.y"], out["ring.moment"] = S[:, 0], S[:, 1], S[:, 2]
    return out


def ring_tie(red, ring_centre=(0.0, 0.0)) -> np.ndarray:
    """(n, n') map ``q = T q'`` tying a reduced housing's bolt patches to a rigid ring: ``q'``
    holds every other coordinate, then the ring's ``(u_x, u_y, theta)`` about ``ring_centre``
    (the last three)."""
    E = red.ring_coupling(ring_centre)
    bolts = sorted(i for p in red.role("bolt") for i in p.coordinates)
    keep = np.setdiff1d(np.arange(red.n), bolts)
    T = np.zeros((red.n, keep.size + 3))
    T[keep, np.arange(keep.size)] = 1.0
    T[bolts, keep.size:] = E[bolts]
    return T


class TransferPath:
    """The reduced housing on its feet, from input channels to sensors (module docstring).

    Parameters
    ----------
    red : HousingReduction
    sensors : sequence of Sensor
        Sensors on the housing, or on the ring when it is tied to the bolts (``ring``).
    inputs : dict, optional
        Channel name -> generalised-force column (n,); default :func:`housing_inputs`.
    damping_ratio : float, optional
        Modal damping ratio zeta in (0, 1); default the housing's ``damping_ratio``.
    ring : (float, float) or None, optional
        A housing with ring bolts: the bolt patches are tied to a rigid ring gear (:func:`ring_tie`)
        of this mass [kg] and polar moment of inertia [kg m^2] about its centre (default
        ``(0, 0)``: a massless rigid ring, the bolt circle held rigid); None leaves the bolts free.
    """

    def __init__(self, red, sensors, inputs=None, damping_ratio=None, ring=(0.0, 0.0)):
        zeta = red.housing.damping_ratio if damping_ratio is None else damping_ratio
        if isinstance(zeta, bool) or not isinstance(zeta, (int, float)) or not 0 < zeta < 1:
            raise ConfigError(f"damping_ratio = {zeta!r}: the housing's modal damping ratio must lie in (0, 1) "
                              "(a path needs damping for its impulse response to decay)")
        self.sensors = tuple(sensors)
        if not self.sensors:
            raise ConfigError("TransferPath: no sensor on the housing")
        inputs = housing_inputs(red) if inputs is None else inputs
        if not inputs:
            raise ConfigError("TransferPath: no input channel (the housing has no seat and no bolt)")
        self.channels = tuple(inputs)
        self.zeta = float(zeta)
        with single_threaded_blas():  # the same bits in any process (a batch's driver or its workers)
            self._modes(red, inputs, ring)

    def _modes(self, red, inputs, ring) -> None:
        """The modes of the housing on its feet (with the tied ring) and their sensor and input
        rows (``omega``, ``_out``, ``_in``)."""
        K, M = red.body.K + red.ground_stiffness(), red.body.M
        T = ring_tie(red) if (ring is not None and red.role("bolt")) else np.eye(red.n)
        K, M = T.T @ K @ T, T.T @ M @ T
        if T.shape[1] != red.n:
            M[-3:, -3:] += np.diag([ring[0], ring[0], ring[1]])
        self.ring = ring if T.shape[1] != red.n else None
        self.tie = T  # q = T q': the model's coordinates (identity without a tied ring)
        w2, Phi = sla.eigh(0.5 * (K + K.T), 0.5 * (M + M.T))
        if w2[0] <= 0:
            raise ConfigError("the housing on its feet has a mode at 0 Hz (no foot, or a foot stiffness of 0): "
                              "give feet with foot_stiffness > 0")
        self.omega = np.sqrt(w2)  # rad/s
        self.order = np.array([QUANTITY_ORDER[s.quantity] for s in self.sensors])
        C = np.array([self._row(red, s, T) for s in self.sensors]).reshape(len(self.sensors), T.shape[1])
        B = T.T @ np.column_stack([np.asarray(inputs[c], float) for c in self.channels])
        self._out = C @ Phi  # (n_s, n)
        self._in = Phi.T @ B  # (n, n_in)

    def _row(self, red, sensor, T) -> np.ndarray:
        """A sensor's row in the model's coordinates: a housing point's recovery row, or a
        point of the tied rigid ring (its last three coordinates)."""
        if sensor.body != "ring":
            return red.sensor_rows([sensor])[0] @ T
        if self.ring is None:
            raise ConfigError(f"sensor {sensor.name!r} is on the ring, not on the housing, and no ring is tied to the "
                              "housing's bolts (a housing with bolts, TransferPath(ring=(mass, inertia)))")
        row = np.zeros(T.shape[1])
        row[-3:] = rigid_row(sensor.point, sensor.direction)
        return row

    @property
    def frequencies(self) -> np.ndarray:
        """Natural frequencies of the housing on its feet [Hz]."""
        return self.omega / (2.0 * math.pi)

    def frf(self, f) -> np.ndarray:
        """Frequency response ``H`` (n_f, n_sensors, n_channels) at frequencies ``f`` [Hz]: each
        sensor's quantity per unit load of a channel [m, m/s, m/s^2 per N or N m]."""
        w = 2.0 * math.pi * np.atleast_1d(np.asarray(f, float))
        g = 1.0 / (self.omega**2 - w[:, None] ** 2 + 2j * self.zeta * self.omega * w[:, None])  # (n_f, n)
        H = np.einsum("sk,fk,kc->fsc", self._out, g, self._in)
        return H * ((1j * w[:, None]) ** self.order[None, :])[:, :, None]

    def decay_samples(self, rate: float) -> int:
        """Samples over which the slowest mode's impulse response decays to :data:`DECAY`."""
        t = math.log(1.0 / DECAY) / (self.zeta * float(self.omega.min()))
        return int(math.ceil(t * rate))

    def impulse_response(self, rate: float, n: int | None = None) -> np.ndarray:
        """Band-limited impulse response (n, n_sensors, n_channels) at ``rate`` [Hz]: the
        response to a unit impulse (1 N s, or 1 N m s) at t = 0, sampled [per N s]; ``n``
        samples (default: its decay, :meth:`decay_samples`)."""
        rate = _check_rate(rate)
        n = self.decay_samples(rate) if n is None else int(n)
        N = sfft.next_fast_len(n + self.decay_samples(rate), real=True)
        H = self.frf(np.fft.rfftfreq(N, 1.0 / rate))
        return rate * sfft.irfft(H, N, axis=0)[:n]

    def response(self, forces, rate: float, periodic: bool = False) -> np.ndarray:
        """Sensor signals (n, n_sensors) of recorded loads, one way (no feedback).

        Parameters
        ----------
        forces : dict or ndarray
            Channel name -> (n,) load [N, N m] (missing channels are zero), or an array (n,
            n_channels) in ``channels`` order; the load the gear set puts on the housing.
        rate : float
            Sample rate [Hz].
        periodic : bool
            False (default): the housing at rest and unloaded before the first sample (a
            static load then starts as a step and rings out). True: the steady-state response
            to the record repeated periodically (no start transient; exact for a record of
            whole periods, e.g. whole carrier revolutions).

        Returns
        -------
        ndarray (n, n_sensors)
            Each sensor's quantity [m, m/s or m/s^2].
        """
        rate = _check_rate(rate)
        F = self._force_array(forces)
        n = F.shape[0]
        N = n if periodic else sfft.next_fast_len(n + self.decay_samples(rate), real=True)
        H = self.frf(np.fft.rfftfreq(N, 1.0 / rate))
        Y = np.einsum("fsc,fc->fs", H, sfft.rfft(F, N, axis=0))
        return sfft.irfft(Y, N, axis=0)[:n]

    def _force_array(self, forces) -> np.ndarray:
        if isinstance(forces, dict):
            unknown = sorted(set(forces) - set(self.channels))
            if unknown:
                raise ConfigError(f"forces: unknown channel(s) {', '.join(map(repr, unknown))}; channels: "
                                  f"{', '.join(self.channels)}")
            lengths = {np.asarray(v).shape for v in forces.values()}
            if len(lengths) != 1 or len(next(iter(lengths))) != 1:
                raise ConfigError(f"forces: every channel must be a 1-D record of one length (shapes {sorted(lengths)})")
            n = next(iter(lengths))[0]
            F = np.zeros((n, len(self.channels)))
            for i, c in enumerate(self.channels):
                if c in forces:
                    F[:, i] = forces[c]
        else:
            F = np.asarray(forces, float)
            if F.ndim != 2 or F.shape[1] != len(self.channels):
                raise ConfigError(f"forces.shape = {F.shape}: must be (n, {len(self.channels)}), channels "
                                  f"{', '.join(self.channels)}")
        if not np.all(np.isfinite(F)):
            raise ConfigError("forces: non-finite values")
        return F


def _check_rate(rate) -> float:
    if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not (math.isfinite(rate) and rate > 0):
        raise ConfigError(f"rate = {rate!r}: the sample rate must be a finite number > 0 Hz")
    return float(rate)


# --------------------------------------------------------------------------------------------
# planet-pass window (McFadden & Smith 1985)
# --------------------------------------------------------------------------------------------
def planet_pass_window(distance, window: str = "hann", width: float = 2.0 * math.pi) -> np.ndarray:
    """The window ``w(d)`` [-] at a planet's angular distance ``d`` from the sensor [rad]
    (wrapped to +-pi): 1 when the planet passes the sensor.

    ``"hann"``: ``(1 + cos(2 pi d / width)) / 2`` for ``|d| < width / 2``, else 0 (the default
    width 2 pi: the raised cosine over the whole carrier revolution); ``"rectangular"``: 1 for
    ``|d| < width / 2``.
    """
    if window not in WINDOWS:
        raise ConfigError(f"window = {window!r}: must be one of {', '.join(WINDOWS)}")
    if not (isinstance(width, (int, float)) and 0 < width <= 2 * math.pi):
        raise ConfigError(f"width = {width!r}: the window's angular width must lie in (0, 2 pi] rad")
    d = (np.asarray(distance, float) + math.pi) % (2 * math.pi) - math.pi
    inside = np.abs(d) < 0.5 * width
    if window == "rectangular":
        return inside.astype(float)
    return np.where(inside, 0.5 * (1.0 + np.cos(2.0 * math.pi * d / width)), 0.0)


def planet_pass_signal(planet_signals, planet_angles, sensor_angle: float, window: str = "hann",
                       width: float = 2.0 * math.pi) -> np.ndarray:
    """The signal a fixed sensor hears: ``y(t) = sum_i w(psi_i(t) - theta_s) x_i(t)``.

    Parameters
    ----------
    planet_signals : ndarray (n, P)
        Each planet's meshing vibration or force x_i (e.g. its recorded planet-ring mesh force)
        [any unit; y has the same].
    planet_angles : ndarray (n, P)
        Angular position psi_i of each planet's centre about the set's centre [rad]
        (``atan2`` of ``/bodies/planet<i>/position``).
    sensor_angle : float
        The sensor's angle theta_s about the set's centre [rad].
    window, width
        :func:`planet_pass_window`.

    Returns
    -------
    ndarray (n,)
    """
    x = np.asarray(planet_signals, float)
    psi = np.asarray(planet_angles, float)
    if x.ndim != 2 or psi.shape != x.shape:
        raise ConfigError(f"planet_signals.shape = {x.shape}, planet_angles.shape = {psi.shape}: both must be (n, P)")
    if not (isinstance(sensor_angle, (int, float)) and math.isfinite(sensor_angle)):
        raise ConfigError(f"sensor_angle = {sensor_angle!r}: must be a finite angle [rad]")
    return np.sum(planet_pass_window(psi - sensor_angle, window, width) * x, axis=1)
