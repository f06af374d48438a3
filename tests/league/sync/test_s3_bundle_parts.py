"""A download that was killed leaves a partial file beside its destination; the next
download of that bundle removes it once it is old, and never a live download's."""

from __future__ import annotations

import os
from pathlib import Path

from league.sync.s3_bundles import S3BundleStore
from league.sync.urls import S3Url
from tests.league.sync.conftest import QUICK_RETRY


def test_a_killed_downloads_partial_file_is_removed_by_the_next_download(
    s3_url: S3Url, tmp_path: Path
) -> None:
    bundles = S3BundleStore(s3_url, retry=QUICK_RETRY)
    bundles.init()
    source = tmp_path / "model.racer-bundle"
    source.write_bytes(os.urandom(50_000))
    ref, _ = bundles.put(source)
    destination = tmp_path / "host" / "model.racer-bundle"
    destination.parent.mkdir()
    killed = destination.parent / f".{destination.name}.k1ll3d.part"
    killed.write_bytes(b"half a bundle")
    stat = killed.stat()
    os.utime(killed, (stat.st_atime - 3600, stat.st_mtime - 3600))
    live = destination.parent / f".{destination.name}.l1v3.part"
    live.write_bytes(b"a download in progress")

    bundles.fetch(ref.sha256, destination)

    assert destination.read_bytes() == source.read_bytes()
    assert not killed.exists()
    assert live.exists()
    bundles.close()
