"""Store URLs: the accepted forms, and one clear sentence for anything else."""

from __future__ import annotations

from pathlib import Path

import pytest

from league.sync.errors import StoreUrlError
from league.sync.stores import open_bundle_store, open_store
from league.sync.urls import DirUrl, DynamoDbUrl, S3Url, parse_store_url


def test_dir_urls_become_absolute_paths(tmp_path: Path) -> None:
    assert parse_store_url(f"dir:{tmp_path}/league") == DirUrl(tmp_path / "league")
    assert parse_store_url("dir:~/league").path == Path.home() / "league"  # type: ignore[union-attr]


def test_dynamodb_url_with_region_and_endpoint() -> None:
    url = parse_store_url("dynamodb://racer-league?region=eu-west-1&endpoint=http://127.0.0.1:8000")
    assert url == DynamoDbUrl("racer-league", "eu-west-1", "http://127.0.0.1:8000")
    assert parse_store_url(str(url)) == url


def test_s3_url_with_prefix() -> None:
    url = parse_store_url("s3://league-bundles/season-1/models?region=us-west-2")
    assert url == S3Url("league-bundles", "season-1/models", "us-west-2", None)
    assert str(url) == "s3://league-bundles/season-1/models?region=us-west-2"


@pytest.mark.parametrize(
    "text",
    [
        "ftp://server/league",
        "dir:",
        "dynamodb://x",
        "dynamodb://league/extra",
        "dynamodb://league?region=narnia",
        "dynamodb://league?regoin=eu-west-1",
        "dynamodb://league?region=eu-west-1&region=us-east-1",
        "dynamodb://league?endpoint=file:///etc/passwd",
        "s3://Bad_Bucket/x",
        "s3://bucket/../escape",
        "s3://bucket/x?endpoint=http://user:pw@host:1",
    ],
)
def test_bad_urls_say_what_the_accepted_forms_are(text: str) -> None:
    with pytest.raises(StoreUrlError) as caught:
        parse_store_url(text)
    message = str(caught.value)
    assert "dir:PATH" in message and "dynamodb://TABLE" in message and "s3://BUCKET" in message
    assert "\n" not in message


def test_an_s3_url_is_for_bundles_not_records() -> None:
    with pytest.raises(StoreUrlError, match="bundles"):
        open_store("s3://league-bundles/x?region=us-east-1")
    with pytest.raises(StoreUrlError, match="s3://"):
        open_bundle_store("dynamodb://league?region=us-east-1")
