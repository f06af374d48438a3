"""Fixtures for the sync tests: a real moto server on loopback, dummy AWS credentials, and
store factories, so DynamoDB and S3 are reached through boto3 exactly as in production."""

from __future__ import annotations

import logging
import uuid
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

from league.sync.protocol import RecordStore
from league.sync.retry import RetryPolicy
from league.sync.stores import open_store
from league.sync.urls import DynamoDbUrl, S3Url

# Small budgets: a store that is down must fail in well under a second in tests.
QUICK_RETRY = RetryPolicy(
    max_attempts=3, base_delay_s=0.01, max_delay_s=0.05, connect_timeout_s=1, read_timeout_s=10
)


class MotoServer:
    """moto in server mode on 127.0.0.1 and a free port, in a thread of this process."""

    def __init__(self) -> None:
        from moto.server import ThreadedMotoServer

        logging.getLogger("werkzeug").setLevel(logging.ERROR)  # no request log on stderr
        self._server = ThreadedMotoServer(ip_address="127.0.0.1", port=0, verbose=False)
        self._server.start()  # returns once the socket is bound and listening
        host, port = self._server.get_host_and_port()
        self.endpoint = f"http://{host}:{port}"

    def stop(self) -> None:
        self._server.stop()


@pytest.fixture(autouse=True)
def aws_env(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Dummy credentials; the real ~/.aws and instance metadata are never consulted."""
    monkeypatch.setenv("AWS_ACCESS_KEY_ID", "testing")
    monkeypatch.setenv("AWS_SECRET_ACCESS_KEY", "testing")
    monkeypatch.setenv("AWS_DEFAULT_REGION", "us-east-1")
    monkeypatch.setenv("AWS_CONFIG_FILE", str(tmp_path / "no-aws-config"))
    monkeypatch.setenv("AWS_SHARED_CREDENTIALS_FILE", str(tmp_path / "no-aws-credentials"))
    monkeypatch.setenv("AWS_EC2_METADATA_DISABLED", "true")
    for name in ("AWS_SESSION_TOKEN", "AWS_PROFILE", "AWS_REGION", "AWS_ENDPOINT_URL"):
        monkeypatch.delenv(name, raising=False)


@pytest.fixture(scope="session")
def moto_server() -> Iterator[MotoServer]:
    server = MotoServer()
    yield server
    server.stop()


@pytest.fixture
def dynamodb_url(moto_server: MotoServer) -> DynamoDbUrl:
    """A fresh table name per test on the shared server."""
    return DynamoDbUrl(f"league-{uuid.uuid4().hex[:12]}", "us-east-1", moto_server.endpoint)


@pytest.fixture
def s3_url(moto_server: MotoServer) -> S3Url:
    return S3Url(
        f"bundles-{uuid.uuid4().hex[:12]}", "league/2026", "us-east-1", moto_server.endpoint
    )


StoreFactory = Callable[[], RecordStore]


@pytest.fixture(params=["dir", "dynamodb"])
def store_kind(request: pytest.FixtureRequest) -> str:
    return str(request.param)


@pytest.fixture
def store_url(store_kind: str, tmp_path: Path, request: pytest.FixtureRequest) -> str:
    """The URL of one shared store, as a league would save it."""
    if store_kind == "dir":
        return f"dir:{tmp_path / 'shared-league'}"
    return str(request.getfixturevalue("dynamodb_url"))


@pytest.fixture
def open_racer_store(store_url: str) -> Iterator[StoreFactory]:
    """Opens a new connection to one shared store (initialised), as another racer would."""
    opened: list[RecordStore] = []

    def factory() -> RecordStore:
        store = open_store(store_url, retry=QUICK_RETRY)
        opened.append(store)
        return store

    factory().init()
    yield factory
    for store in opened:
        store.close()


@pytest.fixture
def organiser_ana_viewer(tmp_path: Path) -> Iterator[dict[str, Any]]:
    """Three machines sharing a folder store: the organiser (who founded it), racer ana
    (admitted) and a viewer."""
    from league.trust import membership
    from tests.league.sync.test_signed_results import Machine

    url = f"dir:{tmp_path / 'shared-league'}"
    with open_store(url) as store:
        store.init()
    made = {name: Machine(tmp_path, name, url) for name in ("organiser", "ana", "viewer")}
    membership.found_league(made["organiser"].league, made["organiser"].key)
    made["organiser"].sync()
    made["ana"].race("ana", [12.0, 11.8])
    made["ana"].sync()  # proposes ana's key
    made["organiser"].sync()
    membership.admit(made["organiser"].league, made["organiser"].key, "ana")
    made["organiser"].sync()
    yield made
    for machine in made.values():
        machine.league.close()
