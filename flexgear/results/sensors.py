"""Sensor signals of a rigid, lumped or flexible run through the simplified path models.

Two path models turn the solver's records into what a ``[[sensors]]`` entry measures, without a
housing in the multi-body model (``docs/guide/housing.md``, *Path models in a run*):

* ``housing_path``: the loads the gear set puts on the housing (:func:`housing_loads`: the
  bearing reactions at the seats, the ring's force and moment through its bolts) applied **one
  way, without feedback**, to the reduced housing on its feet
  (:class:`~flexgear.reduction.paths.TransferPath`); sensors on the housing, and on a ring held
  by its bolts, in the sensor's quantity;
* ``planet_pass``: each planet-ring mesh's normal force weighted by a window of the angle
  between the planet and the sensor, summed over the planets
  (:func:`~flexgear.reduction.paths.planet_pass_signal`; McFadden & Smith 1985); planetary
  sets, housing and ring sensors, in N.

Everything that is not linear and time-invariant (the loads' products of positions and forces,
the planet-pass window) is evaluated on the integration grid and anti-aliased to the output
rate like the forces (:func:`~flexgear.results.decimation.decimate`). The housing path, linear
and time-invariant, is applied to the decimated loads: the low-pass and the path commute, so
the signal in the trustworthy band is the one the path gives at the step rate.

Flexible gears: the records hold each gear's frame (its bore centre) and the mesh forces, so
the loads are the same sums. A gear on an elastic bearing puts its spring-damper force on the
seat exactly; on an ideal joint the sum leaves out the momentum of its elastic modes (its
centre of mass moving against its bore under the mesh load), which the records do not hold.
A flexible ring is held rigid by the path model's bolt tie, like a rigid one.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..dynamics.model.bodies import ANGLE_SPRING, BEARING
from ..errors import ConfigError
from ..fe.elasticity import single_threaded_blas
from ..reduction.paths import TransferPath, housing_inputs, planet_pass_window
from .decimation import decimate, decimate_many
from .store import SensorSignals

#: the housing path's assumption, recorded with its signals
ASSUMPTION = ("one way, no feedback: the loads of a run on a rigid housing drive the reduced housing on its feet; "
              "the housing's motion does not act back on the gears")


@dataclass
class SensorPlan:
    """What a run records at its sensors, prepared before the integration (so that a bad
    sensor or housing fails before any long computation).

    Attributes
    ----------
    sensors : tuple of Sensor
    path : TransferPath or None
        The housing path of the housing sensors (None without ``[housing]`` or housing sensors).
    planet_pass : bool
        Planetary set: every sensor also gets the planet-pass signal.
    coupled : ndarray or None
        ``[housing] coupled = true``: (n_sensors, n_h) displacement rows of the sensors in the
        coupled housing's coordinates (the model holds the housing); None otherwise.
    set_centre : (float, float)
        The gear set's centre [m]: the planets' and sensors' angles are taken about it.
    """

    sensors: tuple
    path: TransferPath | None
    planet_pass: bool
    set_centre: tuple = (0.0, 0.0)
    coupled: np.ndarray | None = None


def check_sensor_run(cfg) -> None:
    """Raise ConfigError, before any long computation, for a ``[housing]`` the run cannot
    serve: a coupled housing on a lumped model, or seating a shaft or ring without an elastic
    support (a table, or a shaft's bending); an absolute noise level at a sensor without a
    housing path."""
    if cfg.housing is None and not cfg.sensors:
        return
    if cfg.housing is not None and cfg.housing.coupled:
        if cfg.model == "lumped":
            raise ConfigError("housing.coupled = true with model = 'lumped': the housing couples into the multi-body "
                              "model (remove model = 'lumped', or set coupled = false for the one-way path models)")
        seated = ("sun", "carrier", "ring") if cfg.kind == "planetary" else tuple(cfg.supports)
        bent = {s["body"] for s in (getattr(cfg, "shafts", None) or {}).values() if s.get("bending")}
        for shaft in seated:
            spec = cfg.supports.get(shaft, "revolute")
            if shaft in bent:  # on its shaft's lateral stiffness: an elastic support
                continue
            what = "the ring, bolted into the housing," if shaft == "ring" else "a shaft seated in the housing"
            if not isinstance(spec, dict):
                raise ConfigError(f"supports.{shaft} = {spec!r} with housing.coupled = true: {what} needs an elastic "
                                  "support, a table {stiffness = N/m, damping = N s/m} (a rigid joint cannot move "
                                  "with the housing)")
            if shaft == "ring" and spec.get("torsional_stiffness") is None:
                raise ConfigError("supports.ring.torsional_stiffness is missing with housing.coupled = true: the "
                                  "ring's reaction torque reaches the housing through its bolts only by a torsional "
                                  "stiffness (N m/rad); without it the ring would be held in rotation by ground")
        return
    heard = heard_by_housing(cfg)
    for s in cfg.sensors:
        if s.noise_rms is not None and s not in heard:
            raise ConfigError(f"sensor {s.name!r}: sensors.noise_rms = {s.noise_rms:g} {s.units}: the sensor records "
                              f"no {s.quantity}, only the planet-pass force (N; a ring on an elastic support, or no "
                              "[housing], has no housing path); give its noise as snr_db")


def ring_held(cfg) -> bool:
    """Whether ``cfg``'s ring gear is held by its bolts (a planetary set whose ``supports.ring``
    is not an elastic table): the ring then moves with the housing and its sensors have a
    housing path."""
    return cfg.kind == "planetary" and not isinstance(cfg.supports.get("ring"), dict)


def heard_by_housing(cfg) -> list:
    """The sensors of ``cfg`` the one-way housing path serves: those on the housing, and those on
    a ring held by its bolts when there is a ``[housing]``."""
    held = ring_held(cfg)
    return [s for s in cfg.sensors if s.body == "housing" or (held and cfg.housing is not None)]


def plan_sensors(cfg, model, progress=None, cache_dir=None) -> SensorPlan | None:
    """Reduce the housing (cached) and set up the path models of ``cfg``'s sensors; None
    without sensors. ``model``: the run's model (the ring's mass, inertia and support);
    ``cache_dir``: the housing cache (default flexgear's mesh cache).

    A ring gear is bolted to the housing: its bolts are tied to it as a rigid body, which
    carries its mass and inertia if it is held by them (``supports.ring = "fixed"``; its
    sensors then have a housing path too); on an elastic support its mass stays with the gears
    and the bolt circle alone is held rigid."""
    check_sensor_run(cfg)
    if cfg.housing is not None and cfg.housing.coupled:
        return _couple(cfg, model, progress, cache_dir)
    if not cfg.sensors:
        return None
    ring = next((b for b in model.bodies if b.name == "ring"), None)
    held = ring is not None and ring_held(cfg)  # the ring moves with the bolts it is held by
    heard = heard_by_housing(cfg)
    path = None
    if heard:
        from ..reduction.housing import USER_CACHE, reduce_housing

        red = reduce_housing(cfg.housing, cache_dir=USER_CACHE if cache_dir is None else cache_dir, progress=progress)
        inertia = (ring.mass, ring.inertia) if held else (0.0, 0.0)
        path = TransferPath(red, heard, inputs=housing_inputs(red, (0.0, 0.0)), ring=inertia)
    return SensorPlan(tuple(cfg.sensors), path, cfg.kind == "planetary")


def _couple(cfg, model, progress, cache_dir) -> SensorPlan:
    """``[housing] coupled = true``: the housing reduced (cached) and put into ``model``
    (:func:`~flexgear.dynamics.model.housing.couple_housing`), its sensors' rows."""
    from ..dynamics.model.housing import couple_housing
    from ..reduction.housing import USER_CACHE, reduce_housing

    for s in cfg.sensors:
        if s.body != "housing":
            raise ConfigError(f"sensor {s.name!r}: sensors.body = {s.body!r} with housing.coupled = true: the coupled "
                              "path records sensors on the housing (use body = 'housing', or coupled = false)")
    red = reduce_housing(cfg.housing, cache_dir=USER_CACHE if cache_dir is None else cache_dir, progress=progress)
    couple_housing(model, red)
    return SensorPlan(tuple(cfg.sensors), None, cfg.kind == "planetary", coupled=red.sensor_rows(cfg.sensors))


def differentiate(y, h: float, order: int) -> np.ndarray:
    """``order``-th time derivative (0, 1, 2) of samples ``y`` (n, ...) of step ``h`` [s] along
    axis 0: fourth-order central differences (amplitude error (omega h)^4 / 30 and / 90), the
    ends one-sided by :func:`numpy.gradient`."""
    y = np.asarray(y, float)
    if order == 0:
        return y.copy()
    if y.shape[0] < 5:
        raise ConfigError(f"a coupled sensor signal needs at least 5 steps, not {y.shape[0]}")
    out = np.gradient(y, h, axis=0, edge_order=2) if order == 1 else np.gradient(
        np.gradient(y, h, axis=0, edge_order=2), h, axis=0, edge_order=2)
    if order == 1:
        out[2:-2] = (-y[4:] + 8 * y[3:-1] - 8 * y[1:-3] + y[:-4]) / (12 * h)
    else:
        out[2:-2] = (-y[4:] + 16 * y[3:-1] - 30 * y[2:-2] + 16 * y[1:-3] - y[:-4]) / (12 * h * h)
    return out


# --------------------------------------------------------------------------------------------
# the loads on the housing
# --------------------------------------------------------------------------------------------
def _mesh_load(model, mesh_rec, i) -> np.ndarray:
    """(n, 2) sum of the mesh forces on body i [N] (``force_global`` is a's force on b)."""
    F = np.zeros((mesh_rec.shape[0], 2))
    for m, mesh in enumerate(model.meshes):
        if mesh.b == i:
            F += mesh_rec[:, m, 1:3]
        if mesh.a == i:
            F -= mesh_rec[:, m, 1:3]
    return F


def _anchor(model, body_rec, i):
    """(position, velocity) (n, 2) of body i's anchor point (its pin, on ground or on its parent)."""
    b = model.bodies[i]
    n = body_rec.shape[0]
    if b.parent < 0:
        return np.broadcast_to(np.asarray(b.pin, float), (n, 2)), np.zeros((n, 2))
    p = body_rec[:, b.parent]
    c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
    rx, ry = c * b.pin[0] - s * b.pin[1], s * b.pin[0] + c * b.pin[1]
    w = p[:, 5]
    return p[:, 0:2] + np.stack([rx, ry], 1), p[:, 3:5] + np.stack([-w * ry, w * rx], 1)


def support_force(model, mesh_rec, body_rec, i, h: float) -> np.ndarray:
    """(n, 2) force [N] that body i, with the bodies it carries, puts on its support (ground or
    its parent), from records on a grid of step ``h`` [s].

    An elastic bearing (BEARING) transmits its spring-damper force. A revolute or fixed joint
    transmits the mesh forces on the body and the forces of the bodies it carries, minus the
    body's mass times its centre's acceleration (Newton). A centre on ground does not move;
    one on a parent whose centre is on ground (a planet on its carrier's pin) moves on a circle,
    ``a = -omega_p^2 r + alpha_p x r``, with ``alpha_p`` the parent's angular acceleration by
    second-order differences of its recorded rate. A flexible body's centre is its frame's (the
    bore); on an ideal joint its elastic modes' momentum is left out (module docstring).
    """
    b = model.bodies[i]
    rec = body_rec[:, i]
    if b.joint == BEARING:
        a, va = _anchor(model, body_rec, i)
        return b.stiffness * (rec[:, 0:2] - a) + b.damping * (rec[:, 3:5] - va)
    F = _mesh_load(model, mesh_rec, i)
    for c, child in enumerate(model.bodies):
        if child.parent == i:
            F += support_force(model, mesh_rec, body_rec, c, h)
    if b.parent >= 0 and b.mass:
        par = model.bodies[b.parent]
        if not (par.parent < 0 and par.joint != BEARING):
            raise ConfigError(f"body {b.name!r}: its parent {par.name!r} is not on a fixed centre; the path models "
                              "need its acceleration (not recorded)")
        p = body_rec[:, b.parent]
        r = rec[:, 0:2] - p[:, 0:2]
        w = p[:, 5]
        alpha = np.gradient(w, h)
        acc = -w[:, None] ** 2 * r + alpha[:, None] * np.stack([-r[:, 1], r[:, 0]], 1)
        F -= b.mass * acc
    return F


def pitch_points(cfg, model, body_rec, m) -> np.ndarray:
    """(n, 2) pitch point of mesh m [m]: where its lines of action cross the line of centres,
    dividing it in the ratio of the base radii (both flanks' lines of action pass through it)."""
    mesh = model.meshes[m]
    g = cfg.gears
    ra, rb = g[model.bodies[mesh.a].attrs["gear"]].rb, g[model.bodies[mesh.b].attrs["gear"]].rb
    xa, xb = body_rec[:, mesh.a, 0:2], body_rec[:, mesh.b, 0:2]
    if mesh.internal:  # a external inside b internal: P beyond a, |O_b P| / |O_a P| = r_b,b / r_b,a
        return xb + (xa - xb) * (rb / (rb - ra))
    return xa + (xb - xa) * (ra / (ra + rb))


def ring_moment(cfg, model, mesh_rec, body_rec, i) -> np.ndarray:
    """(n,) moment [N m] the ring (body i) puts on its support about its centre: a torsional
    spring-damper's, or (ring held in rotation) the moments of the mesh forces on it, each
    acting at its mesh's pitch point (:func:`pitch_points`; exact for frictionless involute
    contact)."""
    b = model.bodies[i]
    rec = body_rec[:, i]
    if b.rotation == ANGLE_SPRING:
        if b.torsion_parent >= 0:
            raise ConfigError(f"body {b.name!r}: a torsional spring to another body; the path models need its "
                              "reaction on the housing")
        return b.torsional_stiffness * (rec[:, 2] - b.theta0) + b.torsional_damping * rec[:, 5]
    M = np.zeros(rec.shape[0])
    for m, mesh in enumerate(model.meshes):
        if i not in (mesh.a, mesh.b):
            continue
        F = mesh_rec[:, m, 1:3] * (1.0 if mesh.b == i else -1.0)
        r = pitch_points(cfg, model, body_rec, m) - rec[:, 0:2]
        M += r[:, 0] * F[:, 1] - r[:, 1] * F[:, 0]
    return M


def housing_loads(cfg, model, mesh_rec, body_rec, h: float, channels) -> np.ndarray:
    """(n, n_channels) loads [N, N m] the gear set puts on the housing, in the order of
    ``channels`` (:func:`~flexgear.reduction.paths.housing_inputs`: ``<shaft>.x``,
    ``<shaft>.y`` at the seats, ``ring.x``, ``ring.y``, ``ring.moment`` through the bolts), from
    records (n, n_meshes, 3: normal force, F_x, F_y of a on b) and (n, n_bodies, 7: x, y, theta,
    v_x, v_y, omega, torque) on a grid of step ``h`` [s]."""
    index = {b.name: i for i, b in enumerate(model.bodies)}
    out = np.zeros((body_rec.shape[0], len(channels)))
    forces = {}
    for k, ch in enumerate(channels):
        body, comp = ch.rsplit(".", 1)
        if body not in index:
            raise ConfigError(f"housing input {ch!r}: the model has no body {body!r}")
        i = index[body]
        if model.bodies[i].parent >= 0:
            raise ConfigError(f"housing input {ch!r}: body {body!r} is not supported on ground")
        if comp == "moment":
            out[:, k] = ring_moment(cfg, model, mesh_rec, body_rec, i)
            continue
        if body not in forces:
            forces[body] = support_force(model, mesh_rec, body_rec, i, h)
        out[:, k] = forces[body][:, "xy".index(comp)]
    return out


def records_of(result, model) -> tuple[np.ndarray, np.ndarray]:
    """A result's signals as the solver's records, in ``model``'s order of meshes and bodies:
    (n, n_meshes, 3: normal force, F_x, F_y of a on b) and (n, n_bodies, 7: x, y, theta, v_x,
    v_y, omega, torque), at the output rate (so :func:`housing_loads` applies to a saved run)."""
    n = result.time.size
    mesh_rec = np.zeros((n, len(model.meshes), 3))
    for m, mesh in enumerate(model.meshes):
        r = result.meshes[mesh.name]
        mesh_rec[:, m, 0], mesh_rec[:, m, 1:3] = r.normal_force, r.force_global
    body_rec = np.zeros((n, len(model.bodies), 7))
    for i, b in enumerate(model.bodies):
        r = result.bodies[b.name]
        body_rec[:, i, 0:2], body_rec[:, i, 2], body_rec[:, i, 3:5], body_rec[:, i, 5] = (
            r.position, r.angle, r.velocity, r.angular_velocity)
        if r.torque is not None:
            body_rec[:, i, 6] = r.torque
    return mesh_rec, body_rec


# --------------------------------------------------------------------------------------------
# a run's sensor signals
# --------------------------------------------------------------------------------------------
def planet_rings(model) -> list:
    """(planet body index, planet-ring mesh index) of every planet, in planet order."""
    out = []
    for m, mesh in enumerate(model.meshes):
        if mesh.internal and model.bodies[mesh.a].name.startswith("planet"):
            out.append((mesh.a, m))
    return sorted(out)


def sensor_angle(sensor, centre=(0.0, 0.0)) -> float:
    """The sensor's angle about the set's centre [rad]."""
    return math.atan2(sensor.point[1] - centre[1], sensor.point[0] - centre[0])


def record_sensors(plan: SensorPlan, cfg, model, mesh_rec, body_rec, h: float, out_every: int, antialias: bool,
                   keep: slice, rate: float, housing_rec=None) -> tuple[dict, dict]:
    """Every sensor's signals (name -> :class:`SensorSignals`) and the loads on the housing
    that drove the housing path (channel -> (n,) [N or N m]; empty without one), from the
    solver's records on the integration grid (step ``h``), anti-aliased and resampled to the
    output rate ``rate`` like the forces (``out_every``, ``antialias``), kept over the output
    samples ``keep``. A coupled housing's signals (``housing_coupled``) read its coordinates
    ``housing_rec`` (nsteps, n_h) at every step."""
    out = {s.name: SensorSignals(s.name, s.definition()) for s in plan.sensors}
    kept_loads = {}
    if plan.coupled is not None and plan.sensors:
        with single_threaded_blas():  # the same bits in any process
            disp = np.asarray(housing_rec) @ plan.coupled.T  # (nsteps, n_sensors) [m]
        order = {"displacement": 0, "velocity": 1, "acceleration": 2}
        ys = decimate_many([differentiate(disp[:, j], h, order[s.quantity]) for j, s in enumerate(plan.sensors)],
                           out_every, antialias, keep)  # every sensor through the filter in one pass
        for s, y in zip(plan.sensors, ys):
            out[s.name].signals["housing_coupled"] = np.ascontiguousarray(y)
            out[s.name].signal_attrs["housing_coupled"] = {
                "units": s.units, "model": "coupled housing", "damping_ratio": float(cfg.housing.damping_ratio),
                "cutoff": float(cfg.housing.cutoff),
                "description": f"{s.quantity} along the sensor's direction, read from the housing's coordinates in "
                "the multi-body model (bearings seated in it, feet on ground springs; two-way coupling)"}
    if plan.path is not None:
        loads = decimate(housing_loads(cfg, model, mesh_rec, body_rec, h, plan.path.channels), out_every, antialias)
        kept_loads = {c: np.ascontiguousarray(loads[keep, k]) for k, c in enumerate(plan.path.channels)}
        y = plan.path.response(loads, rate)[keep]
        attrs = {"model": "housing impulse response", "assumption": ASSUMPTION,
                 "damping_ratio": plan.path.zeta, "cutoff": float(cfg.housing.cutoff),
                 "lowest_mode_hz": float(plan.path.frequencies.min()), "channels": list(plan.path.channels)}
        for j, s in enumerate(plan.path.sensors):
            out[s.name].signals["housing_path"] = np.ascontiguousarray(y[:, j])
            out[s.name].signal_attrs["housing_path"] = dict(
                units=s.units, description=f"{s.quantity} along the sensor's direction through the housing path "
                "(the gear set's loads on the reduced housing, one way)", **attrs)
    if plan.planet_pass:
        pr = planet_rings(model)
        x = mesh_rec[:, [m for _, m in pr], 0]
        pos = body_rec[:, [p for p, _ in pr], 0:2] - np.asarray(plan.set_centre)
        psi = np.arctan2(pos[:, :, 1], pos[:, :, 0])
        angles = [sensor_angle(s, plan.set_centre) for s in plan.sensors]
        ys = decimate_many([np.sum(planet_pass_window(psi - th, s.window, math.radians(s.window_width_deg)) * x, axis=1)
                            for s, th in zip(plan.sensors, angles)], out_every, antialias, keep)
        for s, th, y in zip(plan.sensors, angles, ys):
            out[s.name].signals["planet_pass"] = np.ascontiguousarray(y)
            out[s.name].signal_attrs["planet_pass"] = {
                "units": "N", "description": "planet-ring mesh normal forces weighted by the planet-pass window of "
                "each planet's angle from the sensor, summed over the planets (McFadden & Smith 1985)",
                "model": "planet-pass window", "window": s.window, "window_width_deg": float(s.window_width_deg),
                "sensor_angle_deg": math.degrees(th), "planets": len(pr)}
    return out, kept_loads
