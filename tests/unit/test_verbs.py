"""The one registry of verbs (config/verbs.py) is what the scene checks, the runner, the CLI and
the README read: nothing lists the verbs a second time."""
from __future__ import annotations

import importlib
from pathlib import Path

import pytest

from vibrogear import cli, runner
from vibrogear.config import scene as scene_mod
from vibrogear.config.sections import common as sections
from vibrogear.config.verbs import MODEL_KINDS, VERBS, verb_table_markdown

ROOT = Path(__file__).resolve().parents[2]


def test_readme_verb_table_is_the_registry():
    assert verb_table_markdown() in (ROOT / "README.md").read_text()


def test_every_target_resolves_and_every_output_is_written_by_its_report_package():
    report_src = "".join(p.read_text() for p in (ROOT / "vibrogear" / "report").rglob("*.py"))
    for verb in VERBS.values():
        assert set(verb.models) <= set(MODEL_KINDS), verb.name
        for kind, run in verb.runs.items():
            for package, target in (("analyses", run.analysis), ("report", run.report)):
                module, func = target.split(":")
                mod = importlib.import_module(f"vibrogear.{package}.{module}")
                assert callable(getattr(mod, func)), (verb.name, kind, target)
            for name in run.outputs:
                stem = name.rsplit(".", 1)[0]
                assert f'"{name}"' in report_src or f'"{stem}"' in report_src, (verb.name, name)


def test_consumers_read_the_registry():
    assert set(scene_mod.ANALYSIS_SECTION) == set(VERBS) == set(sections.ANALYSES)
    assert {k: v.section for k, v in VERBS.items()} == scene_mod.ANALYSIS_SECTION
    assert {(kind, v.name) for v in VERBS.values() for kind in v.models} == set(runner.ANALYSIS_TABLE)
    assert set(cli.SINGLE.values()) == {v.name for v in VERBS.values() if v.command}


def test_cli_help_lists_every_command(capsys):
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    text = capsys.readouterr().out
    for verb in VERBS.values():
        if verb.command:
            assert f"run only the {verb.name} analysis" in " ".join(text.split()), verb.name


def test_a_verb_on_the_wrong_model_is_refused_naming_the_field(tmp_path):
    scene = tmp_path / "s.toml"
    scene.write_text('[scene]\nname = "s"\nanalyses = ["campbell"]\n'
                     '[impact_pair]\nzeta = 0.05\nkappa = 0.5\nf_m = 0.55\nf_p = 0.12\nb_r = 1.0\n')
    from vibrogear.config import ConfigError, load_scene
    with pytest.raises(ConfigError, match=r"scene\.analyses\[0\].*campbell"):
        load_scene(scene)


def test_what_a_verb_needs_exists_for_each_of_its_models():
    """``Verb.needs``: the needed verb runs on every model the verb runs on, and takes a
    study only where the verb has one to give it."""
    for verb in VERBS.values():
        for dep in verb.needs:
            assert dep in VERBS and dep != verb.name, (verb.name, dep)
            for kind, run in verb.runs.items():
                assert kind in VERBS[dep].runs, (verb.name, dep, kind)
                assert run.study or not VERBS[dep].runs[kind].study, (verb.name, dep, kind)
    assert VERBS["nvh"].needs == ("modes",)


def test_with_needs_runs_a_needed_verb_once_and_only_where_it_did_not_run(monkeypatch):
    from vibrogear.analyses import invoke as invoke_mod

    calls = []

    def fake_load(target):
        def analysis(study, scene, ctx):
            calls.append((target, study))
            return {"status": "ok", "target": target}
        return analysis

    monkeypatch.setattr(invoke_mod, "load", fake_load)
    seen = invoke_mod.with_needs("nvh", "gearbox", "the study", None, None, {"sweep": 1})
    assert calls == [("vibrogear.analyses.gearbox_modes:run", "the study")]
    assert seen["sweep"] == 1 and seen["modes"].summary["target"].endswith("gearbox_modes:run")
    calls.clear()
    again = invoke_mod.with_needs("nvh", "gearbox", "the study", None, None, seen)
    assert calls == [] and again["modes"] is seen["modes"]
    assert invoke_mod.with_needs("sweep", "gearbox", None, None, None, {}) == {}
    assert calls == []


def test_help_lists_every_command(capsys):
    """``vibrogear --help`` names every command the parser has (the verbs' own commands, run,
    check, import, compare, cache), 17 today."""
    import pytest
    with pytest.raises(SystemExit):
        cli.main(["--help"])
    text = capsys.readouterr().out
    commands = ["run", "check", *[v.command for v in VERBS.values() if v.command], "import",
                "compare", "cache"]
    assert len(commands) == 17
    listed = text.split("commands:", 1)[1].split(".", 1)[0].replace("\n", " ")
    assert [c.strip() for c in listed.split(",")] == commands
