"""``rosaos new-driver`` (rosaos.scaffold): checks before rendering, where it writes, what it prints.

The rendered package's own tests run in a fresh venv in tests/test_template.py (slow).
"""

from __future__ import annotations

import io
from pathlib import Path

import pytest

from rosaos import scaffold
from rosaos.scaffold import new_driver_command


@pytest.fixture(autouse=True)
def in_tmp(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Run in an empty directory, with no terminal on stdin."""
    monkeypatch.chdir(tmp_path)
    monkeypatch.setattr("sys.stdin", io.StringIO())
    return tmp_path


def new_driver(
    name: str | None = "acme_plug",
    dest: Path | None = None,
    *,
    defaults: bool = True,
    title: str | None = None,
    concurrency: str | None = None,
) -> int:
    """``rosaos new-driver`` with these options (the CLI's defaults for the rest)."""
    return new_driver_command(
        name=name,
        title=title,
        description=None,
        concurrency=concurrency,
        author=None,
        dest=dest,
        defaults=defaults,
    )


def test_the_template_is_found_in_a_development_install() -> None:
    assert (scaffold.template_path() / "copier.yml").is_file()


@pytest.mark.parametrize("name", ["Acme", "acme-plug", "9lives", "_acme", ""])
def test_an_invalid_name_is_refused_with_the_rule(name: str, capsys: pytest.CaptureFixture[str]) -> None:
    assert new_driver(name) == 2
    assert "start with a lowercase letter and use only lowercase letters, digits and underscores" in (
        capsys.readouterr().err
    )
    assert list(Path().iterdir()) == []


def test_a_name_is_required_without_a_terminal(capsys: pytest.CaptureFixture[str]) -> None:
    assert new_driver(None) == 2
    assert "give the driver name with --name" in capsys.readouterr().err


def test_an_unknown_concurrency_is_refused(capsys: pytest.CaptureFixture[str]) -> None:
    assert new_driver(concurrency="sometimes") == 2
    assert "--concurrency must be exclusive or shared, not 'sometimes'" in capsys.readouterr().err


def test_unanswered_questions_without_a_terminal_need_defaults(capsys: pytest.CaptureFixture[str]) -> None:
    assert new_driver(defaults=False) == 2
    assert "pass --defaults or every option" in capsys.readouterr().err


def test_an_existing_folder_is_never_overwritten(in_tmp: Path, capsys: pytest.CaptureFixture[str]) -> None:
    (in_tmp / "rosaos-acme_plug").mkdir()
    (in_tmp / "rosaos-acme_plug" / "mine.txt").write_text("keep me", encoding="utf-8")
    assert new_driver() == 2
    assert "rosaos-acme_plug already exists" in capsys.readouterr().err
    assert [p.name for p in (in_tmp / "rosaos-acme_plug").iterdir()] == ["mine.txt"]


def test_it_writes_into_plugins_when_that_folder_exists(
    in_tmp: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (in_tmp / "plugins").mkdir()
    assert new_driver(title="Acme plug", concurrency="shared") == 0
    plugin = in_tmp / "plugins" / "rosaos-acme_plug" / "src" / "rosaos_acme_plug" / "plugin.py"
    assert 'title="Acme plug"' in plugin.read_text(encoding="utf-8")
    out = capsys.readouterr().out
    assert "pip install -e 'plugins/rosaos-acme_plug[test]'" in out
    assert "pytest plugins/rosaos-acme_plug" in out


def test_an_explicit_dest_is_used_as_given(in_tmp: Path) -> None:
    (in_tmp / "plugins").mkdir()
    assert new_driver(dest=in_tmp / "elsewhere") == 0
    assert (in_tmp / "elsewhere" / "rosaos-acme_plug" / "pyproject.toml").is_file()
