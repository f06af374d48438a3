"""Shared by the snapshot tests: a data folder at the same path on every run, so screens
that show paths (the garage's model folder, for example) draw the same characters, and
the same signing key in it (the Sync screen shows its fingerprint)."""

from __future__ import annotations

import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest


@pytest.fixture(autouse=True)
def fixed_home(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    name = request.node.name.replace("[", "-").replace("]", "")
    home = Path(tempfile.gettempdir()) / "racer-tui-snapshots" / name
    shutil.rmtree(home, ignore_errors=True)
    monkeypatch.setenv("RACER_TUI_HOME", str(home))
    _plant_fixed_key(home)
    yield home
    shutil.rmtree(home, ignore_errors=True)


def _plant_fixed_key(home: Path) -> None:
    from cryptography.hazmat.primitives import serialization
    from cryptography.hazmat.primitives.asymmetric.ed25519 import Ed25519PrivateKey

    from league.trust.keys import key_file

    path = key_file(home)
    path.parent.mkdir(parents=True, mode=0o700)
    pem = Ed25519PrivateKey.from_private_bytes(bytes(range(32))).private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )
    path.write_bytes(pem)
    path.chmod(0o600)
