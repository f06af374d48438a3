"""Model bundles in S3 on moto's real server: content-addressed, uploaded once, and
checked for size and hash on the way down."""

from __future__ import annotations

import hashlib
import os
from pathlib import Path

import boto3
import pytest

from league.sync.errors import BundleCorruptError, BundleError, BundleNotFoundError
from league.sync.s3_bundles import S3BundleStore
from league.sync.urls import S3Url
from tests.league.sync.conftest import QUICK_RETRY


@pytest.fixture
def bundles(s3_url: S3Url) -> S3BundleStore:
    store = S3BundleStore(s3_url, retry=QUICK_RETRY)
    store.init()
    store.init()  # idempotent
    return store


@pytest.fixture
def bundle_file(tmp_path: Path) -> Path:
    path = tmp_path / "fast-model.racer-bundle"
    path.write_bytes(os.urandom(300_000))
    return path


def test_a_bundle_round_trips_with_its_hash(
    bundles: S3BundleStore, bundle_file: Path, tmp_path: Path
) -> None:
    ref, uploaded = bundles.put(bundle_file)
    assert uploaded
    assert ref.sha256 == hashlib.sha256(bundle_file.read_bytes()).hexdigest()
    assert ref.key == f"league/2026/bundles/{ref.sha256}.racer-bundle"

    fetched = tmp_path / "host" / "model.racer-bundle"
    assert bundles.fetch(ref.sha256, fetched) == ref
    assert fetched.read_bytes() == bundle_file.read_bytes()


def test_the_same_bundle_is_uploaded_once(bundles: S3BundleStore, bundle_file: Path) -> None:
    first, _ = bundles.put(bundle_file)
    again, uploaded = bundles.put(bundle_file)
    assert not uploaded and again == first
    assert bundles.find(first.sha256) == first


def test_a_tampered_object_is_discarded_not_saved(
    bundles: S3BundleStore, bundle_file: Path, s3_url: S3Url, tmp_path: Path
) -> None:
    ref, _ = bundles.put(bundle_file)
    boto3.client("s3", region_name="us-east-1", endpoint_url=s3_url.endpoint).put_object(
        Bucket=s3_url.bucket, Key=ref.key, Body=b"not the model" * 100
    )
    destination = tmp_path / "host" / "model.racer-bundle"
    with pytest.raises(BundleCorruptError, match="does not match its hash"):
        bundles.fetch(ref.sha256, destination)
    assert list(destination.parent.iterdir()) == []  # no partial or corrupt file left


def test_a_bundle_over_the_size_limit_is_not_downloaded(
    bundles: S3BundleStore, s3_url: S3Url, bundle_file: Path, tmp_path: Path
) -> None:
    ref, _ = bundles.put(bundle_file)
    small = S3BundleStore(s3_url, retry=QUICK_RETRY, max_bytes=100_000)
    with pytest.raises(BundleCorruptError, match="limit"):
        small.fetch(ref.sha256, tmp_path / "model.racer-bundle")
    with pytest.raises(BundleError, match="bundle limit"):
        small.put(bundle_file)
    assert not (tmp_path / "model.racer-bundle").exists()


def test_unknown_and_malformed_hashes(bundles: S3BundleStore, tmp_path: Path) -> None:
    with pytest.raises(BundleNotFoundError, match="not in the S3 bucket"):
        bundles.fetch("0" * 64, tmp_path / "x")
    with pytest.raises(BundleError, match="not a bundle hash"):
        bundles.fetch("../../etc/passwd", tmp_path / "x")
    assert bundles.find("f" * 64) is None
