"""``flexgear modal``: what it tells while it works, and what its report records."""
import re

from flexgear.app.cli import main


def test_modal_names_its_phases_on_stderr(tmp_path, capsys):
    """The phases are told on stderr as ``flexgear run`` tells them (its build message), in
    order: model built, linearisation started (with its positions: 24 for a spur pair, Lin &
    Parker's rule of 8 N for planets), linearised with its time. Before: nothing until the
    result (99 s on a first run of spur_pair_flexible)."""
    assert main(["modal", "spur_pair", "-o", str(tmp_path / "m")]) == 0
    err = capsys.readouterr().err
    lines = [ln for ln in err.splitlines() if ln.startswith("flexgear: ")]
    phases = [next(i for i, ln in enumerate(lines) if pattern.search(ln)) for pattern in (
        re.compile(r"model built in \d+\.\d s"), re.compile(r"linearising about the loaded static equilibrium: "
                                                           r"24 positions over a mesh cycle"),
        re.compile(r"linearised in \d+\.\d s"))]
    assert phases == sorted(phases)
