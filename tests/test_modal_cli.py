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


def test_modal_report_records_its_operating_point_and_configuration(tmp_path, capsys):
    """modes.md and modes.json record the load (the preset's torque on its body), the positions
    (the help's default for a spur pair, 24), the flexgear version and the configuration with
    every default filled in, which parses back to the same load; a spur pair's modes have no
    type, so their type purity is n/a (null in JSON), not 0.0000; the --positions help counts
    positions, not newtons. Before: none of it recorded, "type purity 0.0000", "(default 8 N)"."""
    import json
    import tomllib

    import flexgear
    from flexgear.config import parse_config, preset_path

    out = tmp_path / "m"
    assert main(["modal", "spur_pair", "-o", str(out)]) == 0
    preset = tomllib.loads(preset_path("spur_pair").read_text())
    data = json.loads((out / "modes.json").read_text())
    op = data["operating_point"]
    assert op["load_torques_Nm"] == {preset["load"]["body"]: preset["load"]["torque"]}
    assert op["positions"] == 24 and op["free_drive"] is False
    assert data["flexgear_version"] == flexgear.__version__
    assert parse_config(tomllib.loads(data["config_toml"])).load["torque"] == preset["load"]["torque"]
    assert data["mode_type"] == ["-"] and data["type_purity"] == [None]
    text = (out / "modes.md").read_text()
    assert "## Operating point" in text and "## Version and configuration" in text
    assert data["config_toml"].strip() in text
    row = next(ln for ln in text.splitlines() if ln.startswith("| 1 "))
    assert "n/a" in row and "0.0000" not in row
    capsys.readouterr()
    try:
        main(["modal", "--help"])
    except SystemExit:
        pass
    help_text = " ".join(capsys.readouterr().out.split())
    assert "8 N" not in help_text and "8 per planet, 24 for a spur pair" in help_text


def test_accidental_degeneracy_is_said(tmp_path):
    """MERCURY 1-A at one mesh position: the planet pair and a rotational mode fall on one
    frequency (7442.09 Hz), a multiplicity of 3 where Lin & Parker's rotational mode has 1 and
    the planet pair 2. Every mode whose multiplicity is not its type's is marked accidental in
    the table, with the types that meet, and the report says what that means. Before: the
    rotational mode listed with multiplicity 3 and nothing said."""
    import json

    from flexgear.dynamics.modal.system import expected_multiplicity

    out = tmp_path / "m"
    assert main(["modal", "mercury_1a", "-o", str(out), "--positions", "1"]) == 0
    data = json.loads((out / "modes.json").read_text())
    text = (out / "modes.md").read_text()
    rows = {int(ln.split("|")[1]): ln.split("|")[4].strip() for ln in text.splitlines()
            if ln.startswith("| ") and ln.split("|")[1].strip().isdigit()}
    odd = [i for i, (t, m) in enumerate(zip(data["mode_type"], data["multiplicity"]))
           if m != expected_multiplicity(t, 3, False)]
    assert odd  # the coincidence is there at one position
    for i in range(len(data["frequencies"])):
        assert ("accidental" in rows[i + 1]) == (i in odd), rows[i + 1]
    assert "1 rotational" in rows[odd[0] + 1] and "2 planet" in rows[odd[0] + 1]
    assert "an accidental degeneracy" in text
