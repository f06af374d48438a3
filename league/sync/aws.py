"""boto3 plumbing shared by the DynamoDB and S3 stores: clients, retries, error messages,
and the server's clock.

boto3 finds credentials through the standard AWS chain (environment, ~/.aws, SSO, instance
roles); an `endpoint` from the store URL points the same code at any compatible server
(the tests use moto's server on loopback, exactly like production).
"""

from __future__ import annotations

import email.utils
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, Final, TypeVar

import boto3
import botocore.exceptions
import botocore.loaders
import botocore.session
from botocore.config import Config

from league.sync.errors import (
    StoreAccessDeniedError,
    StoreNotInitialisedError,
    StoreUnavailable,
    StoreUrlError,
    SyncError,
)
from league.sync.retry import RetryPolicy, call_with_retry

if TYPE_CHECKING:
    from mypy_boto3_dynamodb import DynamoDBClient
    from mypy_boto3_s3 import S3Client

T = TypeVar("T")

_THROTTLING: Final = frozenset(
    {
        "ProvisionedThroughputExceededException",
        "ThrottlingException",
        "Throttling",
        "RequestLimitExceeded",
        "RequestThrottled",
        "TooManyRequestsException",
        "SlowDown",
    }
)
_SERVER_TROUBLE: Final = frozenset(
    {"InternalServerError", "InternalError", "ServiceUnavailable", "TransactionInProgressException"}
)
_ACCESS: Final = frozenset(
    {
        "AccessDenied",
        "AccessDeniedException",
        "UnrecognizedClientException",
        "InvalidSignatureException",
        "SignatureDoesNotMatch",
        "InvalidAccessKeyId",
        "InvalidClientTokenId",
        "ExpiredToken",
        "ExpiredTokenException",
        "MissingAuthenticationToken",
    }
)
_MISSING: Final = frozenset({"ResourceNotFoundException", "NoSuchBucket"})
_CONNECTION_ERRORS: Final = (
    botocore.exceptions.ConnectionError,
    botocore.exceptions.HTTPClientError,
)


_loader_lock = threading.Lock()
_shared_loader: list[botocore.loaders.Loader] = []


def new_session() -> boto3.session.Session:
    """A fresh session (credentials and config are read anew) sharing one model loader:
    parsing the service models is most of a client's start-up cost (~150 ms each time)."""
    with _loader_lock:
        if not _shared_loader:
            _shared_loader.append(botocore.loaders.create_loader())
        loader = _shared_loader[0]
    core = botocore.session.get_session()
    core.register_component("data_loader", loader)
    return boto3.session.Session(botocore_session=core)


def resolve_region(region: str | None, endpoint: str | None, url: str) -> str:
    """The URL's region, else the AWS configuration's, else us-east-1 for a custom endpoint."""
    chosen = region or new_session().region_name
    if chosen:
        return chosen
    if endpoint:
        return "us-east-1"  # a self-hosted server ignores the region; signing needs one
    raise StoreUrlError(
        f"no AWS region for {url}: add ?region=eu-west-1 (your region) to the store URL "
        "or set AWS_DEFAULT_REGION"
    )


def client_config(policy: RetryPolicy, pool_size: int) -> Config:
    # botocore's retries are off: retry.call_with_retry is the single retry budget.
    return Config(
        retries={"total_max_attempts": 1, "mode": "standard"},
        connect_timeout=policy.connect_timeout_s,
        read_timeout=policy.read_timeout_s,
        max_pool_connections=pool_size,
        user_agent_extra="racer-tui-sync",
        # Requests are built by this package from validated records; the server checks
        # them anyway. Skipping botocore's client-side walk saves a fifth of a put's CPU.
        parameter_validation=False,
    )


def dynamodb_client(
    region: str, endpoint: str | None, policy: RetryPolicy, pool_size: int
) -> DynamoDBClient:
    return new_session().client(
        "dynamodb",
        region_name=region,
        endpoint_url=endpoint,
        config=client_config(policy, pool_size),
    )


def s3_client(region: str, endpoint: str | None, policy: RetryPolicy, pool_size: int) -> S3Client:
    session = new_session()
    # Path-style addressing works with every S3-compatible server and with dotted buckets.
    config = client_config(policy, pool_size).merge(Config(s3={"addressing_style": "path"}))
    return session.client("s3", region_name=region, endpoint_url=endpoint, config=config)


def error_code(exc: BaseException) -> str:
    if isinstance(exc, botocore.exceptions.ClientError):
        return str(exc.response.get("Error", {}).get("Code", ""))
    return ""


def is_transient(exc: BaseException) -> bool:
    """Worth retrying: connection trouble, throttling, or the server's own failure."""
    if isinstance(exc, _CONNECTION_ERRORS):
        return True
    if isinstance(exc, botocore.exceptions.ClientError):
        status = exc.response.get("ResponseMetadata", {}).get("HTTPStatusCode", 0)
        code = error_code(exc)
        return code in _THROTTLING or code in _SERVER_TROUBLE or status >= 500
    return False


class AwsCaller:
    """Runs boto3 calls with the retry budget and turns failures into one-sentence errors."""

    def __init__(self, description: str, url: str, policy: RetryPolicy) -> None:
        self.description = description
        self.url = url
        self.policy = policy
        self.clock = ServerClock()

    def __call__(self, call: Callable[[], T]) -> T:
        try:
            return call_with_retry(call, is_transient, self.policy)
        except (botocore.exceptions.BotoCoreError, botocore.exceptions.ClientError) as exc:
            raise self.translate(exc) from None

    def translate(self, exc: Exception) -> SyncError:
        where = self.description
        if isinstance(exc, _CONNECTION_ERRORS):
            return StoreUnavailable(
                f"cannot reach {where}: check the network connection and the endpoint in "
                f"the store URL {self.url}, then sync again"
            )
        if isinstance(
            exc,
            botocore.exceptions.NoCredentialsError | botocore.exceptions.PartialCredentialsError,
        ):
            return StoreAccessDeniedError(
                f"no AWS credentials found for {where}: set AWS_PROFILE, or "
                "AWS_ACCESS_KEY_ID and AWS_SECRET_ACCESS_KEY, then sync again"
            )
        code = error_code(exc)
        if code in _THROTTLING:
            return StoreUnavailable(
                f"{where} is still throttling requests after {self.policy.max_attempts} "
                "tries: wait a minute and sync again (what was sent is kept)"
            )
        if code in _ACCESS:
            return StoreAccessDeniedError(
                f"{where} refused the AWS credentials ({code}): check AWS_PROFILE or the "
                "access keys, and that they may use this store"
            )
        if code in _MISSING:
            return StoreNotInitialisedError(
                f"{where} does not exist: run `racer-tui sync init {self.url}` first"
            )
        if is_transient(exc):
            return StoreUnavailable(
                f"{where} keeps failing ({code or type(exc).__name__}): try again later"
            )
        detail = str(exc).replace("\n", " ")[:200]
        return SyncError(f"{where} refused a request ({detail}): check the store URL")


class ServerClock:
    """The store server's idea of now, from the HTTP Date header of its answers.

    Records are ordered by push time; taking that time from the server rather than each
    racer's laptop keeps a laptop with a wrong clock from hiding its pushes behind
    other racers' pull positions. The header has one-second resolution, so offsets
    under two seconds are ignored (the pull overlap window covers them).
    """

    _IGNORE_MS: Final = 2000

    def __init__(self) -> None:
        self._offset_ms = 0
        self._lock = threading.Lock()

    def observe(self, response: Any) -> None:
        try:
            header = response["ResponseMetadata"]["HTTPHeaders"]["date"]
            server_ms = int(email.utils.parsedate_to_datetime(header).timestamp() * 1000)
        except (KeyError, TypeError, ValueError, IndexError):
            return
        offset = server_ms - int(time.time() * 1000)
        with self._lock:
            self._offset_ms = offset if abs(offset) >= self._IGNORE_MS else 0

    def now_ms(self) -> int:
        with self._lock:
            return int(time.time() * 1000) + self._offset_ms
