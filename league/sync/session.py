"""A league's store setting and one sync run, as every front end starts them: the CLI
(`racer-tui sync set`, `racer-tui sync`) and the app's Sync screen call these, so both
accept the same URLs, say the same sentences and push the same things.

    url = saved_store(league)                 # or SyncError: how to set one
    summary, notes = sync_league(league, url, progress=...)
"""

from __future__ import annotations

from league.errors import LeagueError
from league.store import League
from league.sync.engine import Progress, SyncSummary, pull, push, store_key, sync
from league.sync.errors import StoreUrlError, SyncError
from league.sync.local import (
    BUNDLES_SETTING,
    STORE_SETTING,
    clear_failure,
    get_setting,
    record_failure,
    set_setting,
)
from league.sync.protocol import RecordStore
from league.sync.stores import open_bundle_store, open_store
from league.sync.urls import DirUrl, DynamoDbUrl, S3Url, parse_store_url
from league.trust.keys import fingerprint, load_or_create_key
from league.trust.membership import found_league
from league.trust.roster import FOUNDER_ID, PIN_SETTING, Roster
from sim.foundation.plural import counted

PIN_DIGITS = 16  # the whole fingerprint: 8 digits are 32 bits, which a forger can grind

NO_STORE = (
    "this league has no store yet: run `racer-tui sync set STORE` (for example "
    "dir:/mnt/league-share) or pass --store STORE"
)


def check_record_store_url(url: str) -> DirUrl | DynamoDbUrl:
    """A URL a league can sync its records with; StoreUrlError (one sentence) otherwise."""
    store = parse_store_url(url)
    if isinstance(store, S3Url):
        raise StoreUrlError(
            f"{store} holds model bundles, not league records: give a dir: or dynamodb:// "
            "store, and the s3:// URL with --bundles"
        )
    return store


def check_bundle_store_url(url: str) -> S3Url:
    bundles = parse_store_url(url)
    if not isinstance(bundles, S3Url):
        raise StoreUrlError(f"--bundles must be an s3://BUCKET/PREFIX URL, not {bundles}")
    return bundles


def save_store(
    league: League, url: str, bundles_url: str | None = None, *, organiser: str | None = None
) -> tuple[DirUrl | DynamoDbUrl, S3Url | None]:
    """Check and save the league's store (and bundle store, and the organiser's key
    fingerprint as the racer was told it) in one transaction."""
    store = check_record_store_url(url)
    bundles = check_bundle_store_url(bundles_url) if bundles_url else None
    pin = None
    if organiser is not None:
        pin = organiser.replace(" ", "").lower()
        if len(pin) != PIN_DIGITS or not all(c in "0123456789abcdef" for c in pin):
            raise StoreUrlError(
                f"--organiser {organiser!r} is not a key fingerprint: give all "
                f"{PIN_DIGITS} hex digits the organiser reads out from `racer-tui racer keys`"
            )
        founder = Roster.load(league).founder
        if founder is not None and not founder.startswith(pin):
            raise StoreUrlError(
                f"this league's organiser key is {fingerprint(founder)}, not "
                f"{organiser}: check the fingerprint with your organiser"
            )
    with league.transaction():
        set_setting(league, STORE_SETTING, str(store))
        if bundles is not None:
            set_setting(league, BUNDLES_SETTING, str(bundles))
        if pin is not None:
            set_setting(league, PIN_SETTING, pin)
    return store, bundles


def found_store(league: League, store: RecordStore, url: str, *, push_now: bool = True) -> str:
    """What the organiser's set-up does after creating `store`: this machine's key founds
    the league (unless it has an organiser already), and (with `push_now`) the league goes
    to the store at once, so the store names its organiser before any racer syncs. The
    league syncs with this store from now on if it had none. Returns one sentence to show."""
    key = load_or_create_key()
    if push_now:
        # The store may have an organiser already (set up from another machine, or from
        # before signed results): learn it before claiming the league.
        pull(league, store, store_key(url))
    founded = found_league(league, key)
    if get_setting(league, STORE_SETTING) is None:
        save_store(league, url)
    if push_now:
        pushed = push(league, store, store_key(url), signing_key=key)
        if any(FOUNDER_ID in line for line in pushed.conflicts):
            return (
                "This store was already set up by another organiser (its founding record "
                f"names another key than this machine's {key.fingerprint}); use their "
                "machine for the league's admissions, or set up a new store."
            )
    roster = Roster.load(league)
    if founded:
        return f"This machine's key {key.fingerprint} is the league's organiser key."
    if key.public_hex in roster.organisers:
        return f"This league's organiser key is this machine's ({key.fingerprint})."
    founder = fingerprint(roster.founder) if roster.founder else "unknown"
    return (
        f"This league already has an organiser (key {founder}); this machine's key "
        f"{key.fingerprint} is not one of its organiser keys."
    )


def saved_store(league: League, given: str | None = None) -> str:
    """`given`, or the league's saved store; SyncError saying how to set one otherwise."""
    url = given or get_setting(league, STORE_SETTING)
    if url is None:
        raise SyncError(NO_STORE)
    return url


def sync_league(
    league: League,
    url: str,
    *,
    bundles_url: str | None = None,
    push_records: bool = True,
    pull_records: bool = True,
    progress: Progress | None = None,
) -> tuple[SyncSummary, list[str]]:
    """Push the league's model bundles (when a bundle store is set) and records, then pull.

    Returns the summary and notes (one sentence each) about bundles. A store that is down
    raises its SyncError before anything here changes; a failed sync is recorded
    (`league.sync.local.last_failure`) until one succeeds."""
    key = store_key(url)
    try:
        summary, notes = _sync_with(
            league,
            url,
            key=key,
            bundles_url=bundles_url,
            push_records=push_records,
            pull_records=pull_records,
            progress=progress,
        )
    except (SyncError, LeagueError, OSError) as error:
        # Kept until a sync succeeds, so every status line can say the last one failed
        # rather than show the last success as if nothing had happened since.
        with league.transaction():
            record_failure(league, key, str(error))
        raise
    with league.transaction():
        clear_failure(league)
    return summary, notes


def _sync_with(
    league: League,
    url: str,
    *,
    key: str,
    bundles_url: str | None,
    push_records: bool,
    pull_records: bool,
    progress: Progress | None,
) -> tuple[SyncSummary, list[str]]:

    bundles_url = bundles_url or get_setting(league, BUNDLES_SETTING)
    notes: list[str] = []
    with open_store(url) as store:
        if bundles_url and push_records:
            store.push([])  # the record store first: if it is down, nothing changes here
            from league.sync.bundle_sync import push_bundles  # noqa: PLC0415 (boto3: only when bundles are pushed)

            with open_bundle_store(bundles_url) as bundle_store:
                sent = push_bundles(league, bundle_store)
            notes.extend(sent.notes)
            if sent.uploaded:
                notes.append(f"uploaded {counted(sent.uploaded, 'model bundle')} to {bundles_url}")
        summary = sync(
            league,
            store,
            key,
            push_records=push_records,
            pull_records=pull_records,
            progress=progress,
        )
    return summary, notes
