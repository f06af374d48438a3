"""Model bundles through S3 on the loopback server: a racer's sync uploads the bundle of the
model they submitted, and the league host fetches and installs it by its model hash."""

from __future__ import annotations

import io
from contextlib import redirect_stdout
from pathlib import Path

import pytest

from league.assembler import assemble
from league.opening import open_league
from league.submissions import submit
from league.sync.bundle_sync import push_bundles
from league.sync.s3_bundles import S3BundleStore
from league.sync.stores import open_bundle_store
from league.sync.urls import S3Url
from racer_tui.cli.main import main
from sim.garage.folder import open_model
from sim.garage.options import new_model
from tests.league.sync.conftest import QUICK_RETRY
from tests.sim.garage.helpers import add_evaluation, add_policy


def run(*args: str) -> tuple[int, str]:
    out = io.StringIO()
    with redirect_stdout(out):
        code = main(list(args))
    return code, out.getvalue()


@pytest.fixture
def bundles(s3_url: S3Url) -> S3BundleStore:
    store = open_bundle_store(s3_url, retry=QUICK_RETRY)
    store.init()
    return store


def test_a_submitted_model_travels_to_the_host_as_tensors_only(
    s3_url: S3Url, bundles: S3BundleStore, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    model = new_model("speedy")
    policy = add_policy(model, seed=4)
    add_evaluation(model)
    store = f"dir:{tmp_path / 'shared'}"
    assert run("sync", "init", store)[0] == 0
    racer_db, host_db = str(tmp_path / "racer.db"), str(tmp_path / "host.db")
    with open_league(Path(racer_db)) as league:
        submit(league, assemble("speedy", "ana"))
        model_hash = league.query_one("SELECT model_hash FROM submissions")[0]
    assert model_hash == model.content_hash()

    code, out = run("sync", "--db", racer_db, "--store", store, "--bundles", str(s3_url))
    assert code == 0 and "uploaded 1 model bundle" in out
    with open_league(Path(racer_db)) as league:  # a second sync uploads nothing new
        assert push_bundles(league, bundles).uploaded == 0
        assert league.query_one("SELECT count(*) FROM sync_bundles")[0] == 1

    assert run("sync", "--db", host_db, "--store", store)[0] == 0
    code, out = run(
        "sync",
        "fetch-bundle",
        model_hash[:10],
        "--name",
        "fetched",
        "--db",
        host_db,
        "--bundles",
        str(s3_url),
    )
    assert code == 0, out
    assert "Installed model fetched" in out
    fetched = open_model("fetched")
    assert fetched.policy_file.read_bytes() == policy
    assert fetched.content_hash() == model_hash
    assert (fetched.path / "reward_function.bundle.txt").is_file()  # kept as text, never run

    code = main(["sync", "fetch-bundle", "f" * 12, "--db", host_db, "--bundles", str(s3_url)])
    assert code == 2
    assert "no bundle is known" in capsys.readouterr().err
