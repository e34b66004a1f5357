"""``run.check_record_size``: the solver's records are counted before a run, the condensed modes'
record (``Records.condensed``, one value per condensed mode at every output sample, with either
condensation) included, and a run that would not fit is refused before the integration."""
import tomllib

import pytest

import flexgear.app.run as run_module
from flexgear.config import parse_config, preset_path
from flexgear.config.loader import time_grid
from flexgear.dynamics.model.assembly import build_model
from flexgear.dynamics.integrator.simulation import simulate
from flexgear.errors import ConfigError


def flexible_spur(condensation="integrated"):
    doc = tomllib.loads(preset_path("spur_pair_flexible").read_text())
    doc["flexible"].update(level=0, condensation=condensation)
    doc["simulation"].update(duration=0.002, run_in=0.0)
    return parse_config(doc)


@pytest.mark.parametrize("condensation", ["integrated", "static"])
def test_record_estimate_is_the_bytes_the_solver_stores(condensation):
    """The flexible spur pair with its shafts (4 bodies, 101 condensed modes at level 0), 40
    output samples: :func:`record_bytes` with the model equals the bytes of every record the
    solver returns, with both condensations (both record the condensed modes); the condensed
    record is 8 x 101 bytes per output sample of it. Without the model (the check before any
    work) the estimate is a lower bound: it leaves out the shaft bodies and the modes."""
    cfg = flexible_spur(condensation)
    model = build_model(cfg)
    h, every = time_grid(cfg.simulation)
    n_out = 40
    r = simulate(model, n_out * every * h, h, every, alpha=cfg.simulation["hht_alpha"], condensation=condensation)
    stored = sum(a.nbytes for a in r.records)
    n_condensed = sum(fb.shape.shape[3] for fb in model.flex)
    assert n_condensed > 0 and r.records.condensed.shape == (n_out, n_condensed)
    assert r.records.condensed.nbytes == 8 * n_out * n_condensed
    assert run_module.record_bytes(cfg, n_out, every, model) == stored
    assert run_module.record_bytes(cfg, n_out, every) < stored - r.records.condensed.nbytes


def test_run_too_large_for_its_condensed_record_is_refused(monkeypatch):
    """A machine whose memory holds every record but the condensed modes' (half of it is
    between the records without and with ``Records.condensed``): the check before any work
    passes, the one with the built model refuses the run, naming the condensed record, before
    the integration starts."""
    cfg = flexible_spur()
    model = build_model(cfg)
    h, every = time_grid(cfg.simulation)
    rate = cfg.simulation["output_rate"]
    n_out = int(round(cfg.simulation["duration"] * rate)) + max(run_module.TAIL_SAMPLES,
                                                                run_module.settle_samples(every) + 1)
    full = run_module.record_bytes(cfg, n_out, every, model)
    condensed = 8 * n_out * sum(fb.shape.shape[3] for fb in model.flex)
    assert run_module.record_bytes(cfg, n_out, every) < full - condensed
    monkeypatch.setattr(run_module, "memory_bytes", lambda: 2 * (full - condensed // 2))

    def no_integration(*a, **k):
        raise AssertionError("integration started")

    monkeypatch.setattr(run_module, "simulate", no_integration)
    with pytest.raises(ConfigError, match="condensed modes' coordinates") as err:
        run_module.run(cfg, model=model)
    assert "flexible.cutoff" in str(err.value)
    monkeypatch.setattr(run_module, "memory_bytes", lambda: 2 * full)  # it fits: the integration is reached
    with pytest.raises(AssertionError, match="integration started"):
        run_module.run(cfg, model=model)
