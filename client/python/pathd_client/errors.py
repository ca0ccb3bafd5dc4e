"""PathdError and its subclasses, one per gRPC status code a caller may want
to catch, made from a failed call's status and trailing metadata."""

from __future__ import annotations

import grpc

from pathd.v1 import planner_service_pb2

from pathd_client.values import PLAN_OUTCOME_KEY

class PathdError(Exception):
    """A call to pathd failed.

    `code` is the grpc.StatusCode, `details` the server's message, `outcome`
    the PlanOutcome name (e.g. "GOAL_OCCUPIED") when the server sent one, and
    `metadata` every trailing metadata pair (e.g. "retry-after-ms" with
    RESOURCE_EXHAUSTED). Codes with their own subclass below raise that.
    """

    def __init__(self, code: grpc.StatusCode, details: str,
                 metadata: dict[str, str] | None = None):
        super().__init__(f"{code.name}: {details}")
        self.code = code
        self.details = details
        self.metadata = dict(metadata or {})

    @property
    def outcome(self) -> str | None:
        name = self.metadata.get(PLAN_OUTCOME_KEY)
        return name.removeprefix("PLAN_OUTCOME_") if name else None


class NotFoundError(PathdError):
    """NOT_FOUND: no map of that name (or a map_dir file is missing)."""


class InvalidArgumentError(PathdError):
    """INVALID_ARGUMENT: the message names the bad field, cell or line."""


class AlreadyExistsError(PathdError):
    """ALREADY_EXISTS: CreateMap without replace on a taken name."""


class AbortedError(PathdError):
    """ABORTED: UpdateMap's expected_version is not the map's version."""


class FailedPreconditionError(PathdError):
    """FAILED_PRECONDITION: the planner does not apply to this query."""


class ResourceExhaustedError(PathdError):
    """RESOURCE_EXHAUSTED: a queue or limit is full; see retry_after."""

    @property
    def retry_after(self) -> float | None:
        """The server's hint, in seconds, when it gave one."""
        ms = self.metadata.get("retry-after-ms")
        return int(ms) / 1000.0 if ms and ms.isdigit() else None


class DeadlineExceededError(PathdError):
    """DEADLINE_EXCEEDED: the call's deadline (or a session wait) passed."""


class UnavailableError(PathdError):
    """UNAVAILABLE: no server there, or it is shutting down."""


class UnauthenticatedError(PathdError):
    """UNAUTHENTICATED: the server wants a token (PathdClient(token=...))
    and got none, or one it does not know."""


class PermissionDeniedError(PathdError):
    """PERMISSION_DENIED: the token's role may not make this call (a read
    token and UpdateMap, say)."""


_ERROR_CLASSES: dict[grpc.StatusCode, type[PathdError]] = {
    grpc.StatusCode.NOT_FOUND: NotFoundError,
    grpc.StatusCode.INVALID_ARGUMENT: InvalidArgumentError,
    grpc.StatusCode.ALREADY_EXISTS: AlreadyExistsError,
    grpc.StatusCode.ABORTED: AbortedError,
    grpc.StatusCode.FAILED_PRECONDITION: FailedPreconditionError,
    grpc.StatusCode.RESOURCE_EXHAUSTED: ResourceExhaustedError,
    grpc.StatusCode.DEADLINE_EXCEEDED: DeadlineExceededError,
    grpc.StatusCode.UNAVAILABLE: UnavailableError,
    grpc.StatusCode.UNAUTHENTICATED: UnauthenticatedError,
    grpc.StatusCode.PERMISSION_DENIED: PermissionDeniedError,
}

_CODES_BY_NUMBER = {code.value[0]: code for code in grpc.StatusCode}


def make_error(code: grpc.StatusCode, details: str,
               metadata: dict[str, str] | None = None) -> PathdError:
    """The PathdError subclass for `code` (PathdError itself for the rest)."""
    return _ERROR_CLASSES.get(code, PathdError)(code, details, metadata)


def _from_rpc_error(error: grpc.RpcError) -> PathdError:
    # Every RpcError grpc raises for a call is also a grpc.Call.
    trailing = error.trailing_metadata() or ()
    metadata = {key: value for key, value in trailing if isinstance(value, str)}
    return make_error(error.code(), error.details() or "", metadata)


def _from_plan_error(error) -> PathdError:
    """The PathdError of a PlanStream / PlanBatch PlanError message: its
    status code and message, its outcome where Plan's trailing metadata
    would have carried it."""
    code = _CODES_BY_NUMBER.get(error.code, grpc.StatusCode.UNKNOWN)
    metadata = {}
    if error.outcome != planner_service_pb2.PLAN_OUTCOME_UNSPECIFIED:
        metadata[PLAN_OUTCOME_KEY] = planner_service_pb2.PlanOutcome.Name(error.outcome)
    return make_error(code, error.message, metadata)
