"""The files a package carries and the README's promises (issue 36): a short README whose Quick start has its two
commands, a licence the metadata agrees with, a changelog, a citation file, `sflm --version` from the metadata."""

from __future__ import annotations

import importlib
import re
import subprocess
import sys
import tomllib
from importlib.metadata import version
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def test_the_readme_is_short_and_its_quick_start_has_two_commands() -> None:
    text = (ROOT / "README.md").read_text()
    assert len(text.splitlines()) <= 150
    quick = text.split("## Quick start", 1)[1].split("##", 1)[0]
    blocks = re.findall(r"```sh\n(.*?)```", quick, re.S)
    assert len(blocks) == 1
    commands = [line for line in blocks[0].splitlines() if line.strip()]
    assert commands == ['pip install -e . && sflm reproduce paper-sim', 'pip install -e ".[test]" && pytest']
    for needed in ("Python 3.11", "C compiler", "venv", "Licence", "CITATION.cff", "docs/build.py"):
        assert needed in text


def test_the_readme_figure_and_files_exist() -> None:
    text = (ROOT / "README.md").read_text()
    for path in re.findall(r"\]\(([^)#]+)\)", text):
        assert (ROOT / path).exists(), path


def test_the_licence_is_the_metadata_s() -> None:
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert meta["license"]["text"] == "BSD-3-Clause"
    assert "License :: OSI Approved :: BSD License" in meta["classifiers"]
    assert (ROOT / "LICENSE").read_text().startswith("BSD 3-Clause License")


def test_the_changelog_and_the_citation_name_this_version() -> None:
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    assert f"## {meta['version']}" in (ROOT / "CHANGELOG.md").read_text()
    citation = (ROOT / "CITATION.cff").read_text()
    assert f"version: {meta['version']}" in citation and "cff-version: 1.2.0" in citation
    assert "Transactions of the Canadian Society for Mechanical Engineering" in citation


def test_the_readme_claims_the_systems_the_classifiers_name() -> None:
    # issue 49: the classifiers said Linux only while the README promised macOS too
    meta = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]
    systems = [c.split("::")[-1].strip() for c in meta["classifiers"] if c.startswith("Operating System")]
    requirement = next(line for line in (ROOT / "README.md").read_text().splitlines() if "macOS" in line or "Linux" in line)
    assert systems == ["Linux"] and requirement.startswith("* Linux (") and "not tested" in requirement


def test_the_version_comes_from_the_metadata() -> None:
    out = subprocess.run([sys.executable, "-m", "sflm", "--version"], capture_output=True, text=True, check=True).stdout
    assert out.strip() == f"sflm {version('sflm')}"
    import modelgen

    assert modelgen.__version__ == version("sflm")  # the paper report's stamp, from the same source
    # one source: pyproject.toml; no module writes the number again (CITATION.cff and the changelog are checked above)
    number = f'"{version("sflm")}"'
    assert [p for top in ("modelgen", "inversion", "simulation", "sflm") for p in (ROOT / top).rglob("*.py")
            if number in p.read_text()] == []


def test_the_cli_reference_has_every_flag() -> None:
    from sflm.cli import _parser
    from sflm.cli_reference import reference_markdown

    parser = _parser()
    text = reference_markdown(parser)
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    for name, command in sub.choices.items():
        assert f"## `sflm {name}`" in text
        for action in command._actions:
            for flag in action.option_strings:
                if flag not in ("-h", "--help"):
                    assert f"`{flag}" in text or f", {flag}" in text, (name, flag)


def test_every_command_has_an_example_that_its_parser_takes(capsys: pytest.CaptureFixture[str],
                                                           monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 58, item 1: one example per command, printed by ``sflm COMMAND --help`` and in a code block on the command
    reference; the parser takes it as written (its files are the repository's, its flags the command's own)."""
    import shlex

    from sflm.cli import _parser, main
    from sflm.cli_reference import reference_markdown

    parser = _parser()
    text = reference_markdown(parser)
    sub = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    monkeypatch.setenv("COLUMNS", "100000")
    for name, command in sub.choices.items():
        example = importlib.import_module(f"sflm.cli.{name}").EXAMPLE
        words = shlex.split(example)
        assert words[:2] == ["sflm", name], example
        parsed = parser.parse_args(words[1:])  # a flag the command lacks would exit 2 here
        assert parsed.command == name
        model = words[2]
        assert model in ("paper-sim", "paper-exp") or (ROOT / model).is_file(), example
        section = text.split(f"## `sflm {name}`")[1].split("\n## ")[0]
        assert f"```sh\n{example}\n```" in section, name
        with pytest.raises(SystemExit):
            main([name, "--help"])
        assert example in capsys.readouterr().out, name


@pytest.mark.parametrize("command", ["info", "invert", "fit", "simulate", "compare"])
def test_the_cli_reference_is_the_help_word_for_word(command: str, capsys: pytest.CaptureFixture[str],
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """Issue 49, item 6: each argument's text in the reference is what ``sflm COMMAND --help`` prints (no ``%%``, no
    ``%(default)s``), and the documentation's build keeps ``--flag`` two hyphens (no smart quotes)."""
    import re

    from sflm.cli import _parser, main
    from sflm.cli_reference import reference_markdown

    text = reference_markdown(_parser())
    assert "%%" not in text and "%(" not in text
    monkeypatch.setenv("COLUMNS", "100000")  # no wrapping: argparse breaks lines at hyphens too
    with pytest.raises(SystemExit):
        main([command, "--help"])
    printed = " ".join(capsys.readouterr().out.split())
    section = text.split(f"## `sflm {command}`")[1].split("\n## ")[0]
    import html

    cells = [html.unescape(row.split(" | ")[-1].rstrip(" |").replace("\\|", "|")) for row in section.splitlines()
             if row.startswith("| `")]
    assert cells
    for cell in cells:
        assert cell in printed, cell
    conf = (Path(__file__).resolve().parents[2] / "docs" / "conf.py").read_text()
    assert re.search(r"^smartquotes = False$", conf, re.M)


def test_the_readme_command_line_example_runs(tmp_path, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    import shlex

    from sflm.cli import main

    text = (ROOT / "README.md").read_text()
    block = text.split("from the command line", 1)[1].split("```sh", 1)[1].split("```", 1)[0]
    (tmp_path / "tests").symlink_to(ROOT / "tests")
    monkeypatch.chdir(tmp_path)
    commands = [line.split("#", 1)[0] for line in block.splitlines() if line.startswith("sflm ")]
    assert len(commands) == 3
    for command in commands:
        assert main(shlex.split(command)[1:]) == 0, command
    assert (tmp_path / "ff" / "feedforward.h").is_file()


def test_every_package_goes_into_the_wheel() -> None:
    # pyproject's package discovery finds every folder with an __init__.py under the four packages (a list of the four
    # names alone once left inversion.family.ssef out of the wheel: the editable install hid it)
    find_packages = pytest.importorskip("setuptools").find_packages

    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    found = set(find_packages(where=str(ROOT), include=config["packages"]["find"]["include"]))
    expected = {str(p.parent.relative_to(ROOT)).replace("/", ".") for top in ("modelgen", "inversion", "simulation", "sflm")
                for p in (ROOT / top).rglob("__init__.py")}
    assert found == expected
    assert "presets/*.toml" in config["package-data"]["modelgen"]
