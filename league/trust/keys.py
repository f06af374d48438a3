"""This machine's signing key: one Ed25519 key per racer-tui data directory.

The key signs every record this machine shares (seals.py). It is made on first use and
kept in `<data home>/keys/league-signing.pem`, readable by its owner only; a key file
that others can read is refused rather than used, the way ssh treats a private key.
Creating it is atomic and race-free (written aside, then linked into place), so two
processes starting at once end up with the same key.

Public keys travel as 64 lowercase hex digits; people compare them by their fingerprint,
the first 16 digits in groups of four.
"""

from __future__ import annotations

import contextlib
import os
import stat
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Final

from cryptography.exceptions import InvalidSignature
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric.ed25519 import (
    Ed25519PrivateKey,
    Ed25519PublicKey,
)

from league.errors import LeagueError
from sim.foundation.home import data_home

KEY_DIR: Final = "keys"
KEY_FILE: Final = "league-signing.pem"
PUBLIC_HEX_CHARS: Final = 64
SIGNATURE_HEX_CHARS: Final = 128


class KeyFileError(LeagueError):
    """The signing key file cannot be used (one sentence saying what to do)."""


@dataclass(frozen=True)
class SigningKey:
    """A private key and its public half, as hex."""

    private: Ed25519PrivateKey
    public_hex: str

    @classmethod
    def generate(cls) -> SigningKey:
        return cls.from_private(Ed25519PrivateKey.generate())

    @classmethod
    def from_private(cls, private: Ed25519PrivateKey) -> SigningKey:
        raw = private.public_key().public_bytes(
            serialization.Encoding.Raw, serialization.PublicFormat.Raw
        )
        return cls(private, raw.hex())

    def sign(self, message: bytes) -> str:
        return self.private.sign(message).hex()

    @property
    def fingerprint(self) -> str:
        return fingerprint(self.public_hex)


def fingerprint(public_hex: str) -> str:
    """What a person reads aloud to check a key: `ab12 cd34 ef56 7890`."""
    head = public_hex[:16]
    return " ".join(head[start : start + 4] for start in range(0, len(head), 4))


def is_public_hex(text: object) -> bool:
    return (
        isinstance(text, str)
        and len(text) == PUBLIC_HEX_CHARS
        and all(char in "0123456789abcdef" for char in text)
    )


def verify(public_hex: str, message: bytes, signature_hex: str) -> bool:
    """Whether `signature_hex` is `public_hex`'s signature of `message`; never raises."""
    try:
        public = Ed25519PublicKey.from_public_bytes(bytes.fromhex(public_hex))
        public.verify(bytes.fromhex(signature_hex), message)
    except (InvalidSignature, ValueError):
        return False
    return True


def key_file(home: Path | None = None) -> Path:
    return (home if home is not None else data_home()) / KEY_DIR / KEY_FILE


def load_or_create_key(home: Path | None = None) -> SigningKey:
    """This data directory's signing key, made now if it has none (KeyFileError if the
    file exists but cannot be used)."""
    path = key_file(home)
    if not path.exists():
        _create(path)
    return _load(path)


def _create(path: Path) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    os.chmod(path.parent, 0o700)
    pem = Ed25519PrivateKey.generate().private_bytes(
        serialization.Encoding.PEM,
        serialization.PrivateFormat.PKCS8,
        serialization.NoEncryption(),
    )
    handle, temp_name = tempfile.mkstemp(dir=path.parent, prefix=".key-")
    try:
        os.fchmod(handle, 0o600)
        os.write(handle, pem)
        os.fsync(handle)
        os.close(handle)
        # Fails if another process made the key first: then theirs is the key.
        with contextlib.suppress(FileExistsError):
            os.link(temp_name, path)
    finally:
        os.unlink(temp_name)


def _load(path: Path) -> SigningKey:
    try:
        mode = path.stat().st_mode
        if mode & (stat.S_IRWXG | stat.S_IRWXO):
            raise KeyFileError(
                f"the signing key {path} can be read by other users; make it private with "
                f"`chmod 600 {path}` and try again."
            )
        data = path.read_bytes()
    except OSError as error:
        raise KeyFileError(
            f"the signing key {path} cannot be read ({error.strerror}); check its permissions."
        ) from None
    try:
        private = serialization.load_pem_private_key(data, password=None)
    except (ValueError, TypeError):
        private = None
    if not isinstance(private, Ed25519PrivateKey):
        raise KeyFileError(
            f"{path} is not an Ed25519 signing key; move it aside and racer-tui makes a new "
            "one (the league's organiser must then admit the new key)."
        )
    return SigningKey.from_private(private)
