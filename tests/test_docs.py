"""The documentation cannot drift from the code: the configuration reference is generated from
the loader's schema, and every key the loader accepts is in it.

The loader validates each table of a configuration against a schema dict, key -> (kind,
default, rule, unit, description). A table joins the reference by being registered in
``flexgear.config.loader.SECTIONS``; these tests fail for a schema dict or a top-level table
that is not registered, for a key without a description, and for a registered key that the
generated text does not show. (The docs build itself runs in ``.ci/run``.)
"""
import importlib
import pkgutil
import re
from pathlib import Path

import pytest

import flexgear.config
from flexgear.config import loader
from flexgear.config.lumped_parameters import MEMBER_KEYS, PARAMETER_KEYS
from flexgear.config.reference import heading, labels, reference_markdown

ROOT = Path(__file__).resolve().parents[1]
KINDS = {"float", "int", "bool", "str", "profile", "any"}


def schema_dicts():
    """Every module-level schema of the configuration layer: a dict of key -> (kind, ...)."""
    for info in pkgutil.iter_modules(flexgear.config.__path__):
        module = importlib.import_module(f"flexgear.config.{info.name}")
        for name, value in vars(module).items():
            if (isinstance(value, dict) and value and name.isupper()
                    and all(isinstance(v, tuple) and v and v[0] in KINDS for v in value.values())):
                yield f"{info.name}.{name}", value


def section_text(text, section, sections=loader.SECTIONS):
    """The generated text of one section: from its label to the next label."""
    start = text.index(f"({labels(sections)[sections.index(section)]})=")
    end = text.find("\n(config-", start + 1)
    return text[start:] if end < 0 else text[start:end]


def test_every_schema_of_the_configuration_layer_is_registered():
    registered = [s.keys for s in loader.SECTIONS]
    missing = [name for name, d in schema_dicts() if not any(d is r or d == r for r in registered)
               and not any(set(d) > set(r) for r in registered)]
    assert not missing, f"schemas not registered in flexgear.config.loader.SECTIONS: {missing}"


def test_every_top_level_table_is_registered():
    documented = {s.name.split(".")[0] for s in loader.SECTIONS if s.name} | set(loader.TOP_LEVEL_KEYS)
    missing = sorted(loader.TOP_KEYS - documented)
    assert not missing, f"top-level keys the loader accepts but SECTIONS does not document: {missing}"


def test_lumped_parameters_registered_are_those_validated():
    sections = {s.name: s.keys for s in loader.SECTIONS}
    assert tuple(sections["lumped.parameters"]) == PARAMETER_KEYS
    assert tuple(sections["lumped.parameters.<member>"]) == MEMBER_KEYS


@pytest.mark.parametrize("section", loader.SECTIONS, ids=lambda s: s.name or "top")
def test_every_key_has_a_kind_unit_and_description(section):
    for key, spec in section.keys.items():
        assert len(spec) == 5, f"{section.name}.{key}: (kind, default, rule, unit, description) expected"
        kind, _, _, unit, description = spec
        assert kind in KINDS and isinstance(unit, str), f"{section.name}.{key}"
        assert description.strip(), f"{section.name}.{key} has no description"


def test_every_accepted_key_appears_in_the_generated_reference():
    text = reference_markdown()
    for section in loader.SECTIONS:
        part = section_text(text, section)
        assert heading(section) in part
        for key in section.keys:
            row = re.compile(rf"^\| `{re.escape(key)}` \|", re.M)
            listed = f"`{key}`" in part if section.same_keys else row.search(part)
            assert listed, f"[{section.name}] {key} is not in the generated reference"


def test_reference_rows_show_default_rule_and_unit():
    text = section_text(reference_markdown(), next(s for s in loader.SECTIONS if s.name == "simulation"))
    assert "| `step` | number | `2.5e-05` | > 0 | s |" in text
    assert '| `units` | string | `"N-mm"` | "SI", "N-mm" |' in section_text(
        reference_markdown(), next(s for s in loader.SECTIONS if s.name == "contact"))


def test_the_reference_page_includes_the_generated_text():
    page = (ROOT / "docs" / "configuration.md").read_text()
    conf = (ROOT / "docs" / "conf.py").read_text()
    assert "```{include} _generated/configuration_keys.md" in page
    assert "reference_markdown()" in conf and '"_generated" / "configuration_keys.md"' in conf


def test_a_new_table_joins_the_reference_by_registration():
    faults = {"kind": ("str", None, ("crack", "spall"), "", "the fault's kind")}
    section = loader.Section("faults", faults, "Tooth faults.", array=True)
    sections = loader.SECTIONS + (section,)
    text = reference_markdown(sections)
    assert "## `[[faults]]`" in text and "| `kind` | string |" in section_text(text, section, sections)


def test_no_raw_angle_brackets_outside_code():
    """Markdown reads ``<name>`` outside a code span as an HTML tag and drops it from the page."""
    text = reference_markdown().split("\n", 1)[1]  # the first line is the generator's comment
    outside = re.sub(r"`[^`]*`", "", text)
    assert not re.search(r"<[A-Za-z/]", outside), re.search(r".*<[A-Za-z/].*", outside).group(0)


def test_every_docs_page_the_code_and_readme_name_exists():
    """Help texts, messages, preset comments, studies and README point users at docs pages by
    path: each must exist (``flexgear monitor -h`` named docs/monitoring.md, a page that never was)."""
    named = set()
    for folder in ("flexgear", "studies", "benchmarks", "examples"):
        for path in (ROOT / folder).rglob("*"):
            if path.suffix in (".py", ".toml") and "__pycache__" not in path.parts:
                named |= set(re.findall(r"docs/[\w/.-]+?\.(?:md|rst)\b", path.read_text()))
    named |= set(re.findall(r"docs/[\w/.-]+?\.(?:md|rst)\b", (ROOT / "README.md").read_text()))
    assert len(named) > 10
    built = ("docs/_generated/", "docs/_build/", "docs/auto_examples/")  # what the docs build writes
    missing = sorted(p for p in named if not (ROOT / p).exists() and not p.startswith(built))
    assert not missing, f"pages named but absent: {missing}"
    readme = (ROOT / "README.md").read_text()
    sections = set(re.findall(r"^#+ (.+)$", readme, re.M))
    for folder in ("flexgear", "studies"):
        for path in (ROOT / folder).rglob("*"):
            if path.suffix in (".py", ".toml"):
                for section in re.findall(r"README[,]? ['\"]([^'\"]+)['\"]", path.read_text()):
                    assert section in sections, f"{path.name}: README has no section {section!r}"


def test_the_docs_name_the_current_result_layout():
    """Every page that names the result file's ``layout_version`` names the one written."""
    from flexgear.results.store import LAYOUT_VERSION

    root = Path(__file__).resolve().parents[1]
    for page in [root / "README.md", *sorted((root / "docs").rglob("*.md"))]:
        if "_build" in page.parts:
            continue
        for n in re.findall(r"`layout_version` (\d+)", page.read_text()):
            assert int(n) == LAYOUT_VERSION, page.name


def test_a_study_run_as_a_program_refuses_as_the_commands_do(tmp_path, monkeypatch, capsys):
    """A study's error ends the program with one line and status 2, as ``flexgear``'s commands
    (a trial's rerun of rigid_vs_flexible.py into its own output printed ResultExistsError's
    traceback): every script in studies/ ends through flexgear.app.console.run_command, and
    rigid_vs_flexible.py given an existing report says so before simulating anything."""
    import runpy
    import sys

    root = Path(__file__).resolve().parents[1]
    for path in sorted(root.glob("studies/*.py")):
        assert path.read_text().rstrip().endswith("sys.exit(run_command(main, Path(__file__).stem))"), path.name
    (tmp_path / "report.md").write_text("kept")
    monkeypatch.setattr(sys, "argv", ["rigid_vs_flexible.py", "-o", str(tmp_path), "--quick"])
    with pytest.raises(SystemExit) as done:
        runpy.run_path(str(root / "studies" / "rigid_vs_flexible.py"), run_name="__main__")
    err = capsys.readouterr().err
    assert done.value.code == 2 and "Traceback" not in err, err
    assert re.fullmatch(r"rigid_vs_flexible: error: '.*report\.md' already exists; refusing to overwrite it \(.*\)\n",
                        err), err
    assert (tmp_path / "report.md").read_text() == "kept"


def test_every_study_and_benchmark_answers_help(monkeypatch, capsys):
    """``--help`` of every script in studies/ and benchmarks/ prints its options and exits 0: a
    literal percent sign in an option's help ended in argparse's TypeError. A study that writes
    to a directory takes it as ``-o``, ``--output`` or ``--out`` (the studies had mixed them)."""
    import runpy
    import sys

    root = Path(__file__).resolve().parents[1]
    monkeypatch.syspath_prepend(str(root / "benchmarks"))
    for path in sorted([*root.glob("studies/*.py"), *root.glob("benchmarks/bench_*.py")]):
        monkeypatch.setattr(sys, "argv", [str(path), "--help"])
        with pytest.raises(SystemExit) as done:
            runpy.run_path(str(path), run_name="__main__")
        assert done.value.code == 0, path.name
        out = capsys.readouterr().out
        assert "usage:" in out, path.name
        if path.parent.name == "studies" and ("--out" in out or "--output" in out):
            spellings = re.search(r"-o (\w+), (--out(?:put)?) \1, (--out(?:put)?) \1", out)
            assert spellings and {spellings[2], spellings[3]} == {"--out", "--output"}, path.name
