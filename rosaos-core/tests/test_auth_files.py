"""The token and the data directory are the owner's alone."""

from __future__ import annotations

import stat
from pathlib import Path

from rosaos.auth import load_or_create_token, token_path


def _mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def test_a_new_data_directory_and_its_token_are_owner_only(tmp_path: Path) -> None:
    data_dir = tmp_path / "fresh" / "rosaos"
    token = load_or_create_token(data_dir)
    assert len(token) >= 32
    assert _mode(data_dir) == 0o700
    assert _mode(token_path(data_dir)) == 0o600


def test_an_existing_world_readable_data_directory_is_narrowed(tmp_path: Path) -> None:
    data_dir = tmp_path / "rosaos"
    data_dir.mkdir(mode=0o755)
    data_dir.chmod(0o755)
    first = load_or_create_token(data_dir)
    assert _mode(data_dir) == 0o700
    assert load_or_create_token(data_dir) == first  # the token is kept, not replaced
