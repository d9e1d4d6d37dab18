"""Errors of the lightfarm client: one class per gRPC status code the farm answers with.

Every error carries the gRPC status code (``code``, a :class:`grpc.StatusCode`) and the server's
own message (``message``), e.g. the scene loader's for a malformed scene::

    try:
        client.submit("scene.json")
    except lightfarm.InvalidArgument as e:
        print(e.message)
"""

from __future__ import annotations

from typing import Optional

import grpc


class LightfarmError(Exception):
    """A call to lightfarm-server failed (or its arguments were refused before any call)."""

    #: The gRPC status code this class stands for.
    default_code: grpc.StatusCode = grpc.StatusCode.UNKNOWN

    def __init__(self, message: str, code: Optional[grpc.StatusCode] = None) -> None:
        super().__init__(message)
        self.message = message
        self.code = code if code is not None else self.default_code

    def __str__(self) -> str:
        return f"{self.code.name}: {self.message}"


class InvalidArgument(LightfarmError):
    """The request was refused: a malformed scene (with the loader's message), a setting out of
    range, a file the scene names that cannot be read here."""
    default_code = grpc.StatusCode.INVALID_ARGUMENT


class NotFound(LightfarmError):
    """No such job (or, for a submitter, not one of its own)."""
    default_code = grpc.StatusCode.NOT_FOUND


class AlreadyExists(LightfarmError):
    default_code = grpc.StatusCode.ALREADY_EXISTS


class PermissionDenied(LightfarmError):
    """The token's role may not make this call (a worker token submitting, say)."""
    default_code = grpc.StatusCode.PERMISSION_DENIED


class Unauthenticated(LightfarmError):
    """No token, or a token the server does not know (or has revoked)."""
    default_code = grpc.StatusCode.UNAUTHENTICATED


class FailedPrecondition(LightfarmError):
    """The job is not in a state for this: fetching an unfinished job, cancelling an ended one,
    deleting a running one."""
    default_code = grpc.StatusCode.FAILED_PRECONDITION


class ResourceExhausted(LightfarmError):
    """A server limit: too many watchers, a scene too large, ..."""
    default_code = grpc.StatusCode.RESOURCE_EXHAUSTED


class Aborted(LightfarmError):
    """Another client uploads the same blob now (submit retries this itself)."""
    default_code = grpc.StatusCode.ABORTED


class OutOfRange(LightfarmError):
    default_code = grpc.StatusCode.OUT_OF_RANGE


class Unimplemented(LightfarmError):
    """The server is of a version without this call."""
    default_code = grpc.StatusCode.UNIMPLEMENTED


class Unavailable(LightfarmError):
    """The server cannot be reached (down, restarting, a wrong address)."""
    default_code = grpc.StatusCode.UNAVAILABLE


class TlsError(LightfarmError):
    """The TLS handshake failed: a wrong CA, a certificate that does not name the server, a
    plain-text server, or a client certificate the server refuses. gRPC reports it as
    UNAVAILABLE (``code``), but retrying cannot help, so it is not an :class:`Unavailable`."""
    default_code = grpc.StatusCode.UNAVAILABLE


class DeadlineExceeded(LightfarmError):
    default_code = grpc.StatusCode.DEADLINE_EXCEEDED


class Cancelled(LightfarmError):
    default_code = grpc.StatusCode.CANCELLED


class Internal(LightfarmError):
    default_code = grpc.StatusCode.INTERNAL


_BY_CODE = {cls.default_code: cls for cls in (
    InvalidArgument, NotFound, AlreadyExists, PermissionDenied, Unauthenticated,
    FailedPrecondition, ResourceExhausted, Aborted, OutOfRange, Unimplemented, Unavailable,
    DeadlineExceeded, Cancelled, Internal)}


def from_rpc_error(error: grpc.RpcError, server: str = "", call: str = "",
                   tls: bool = False) -> LightfarmError:
    """The :class:`LightfarmError` for a failed gRPC call (``call``, a JobService method, for
    a message when the server gives none; ``tls``, whether the client speaks TLS), with the
    server's message."""
    code = error.code() if hasattr(error, "code") else grpc.StatusCode.UNKNOWN
    details = error.details() if hasattr(error, "details") else None
    if not details:
        if code == grpc.StatusCode.UNIMPLEMENTED:
            details = f"{call or 'the call'}: not implemented by server {server}"
        else:
            details = f"{call or 'the call'}: {code.name} without a message"
    if code == grpc.StatusCode.UNAVAILABLE and tls and ("wrong version number" in details or
                                                        "WRONG_VERSION_NUMBER" in details):
        return TlsError(f"server {server} does not speak TLS (it answered the TLS handshake in "
                        f"plain text): leave out tls_ca, or start the server with --tls-cert "
                        f"and --tls-key ({details})", code)
    if code == grpc.StatusCode.UNAVAILABLE and tls and "ALPN" in details:
        return TlsError(f"server {server} speaks TLS but not gRPC (is it the server's --http "
                        f"port?) ({details})", code)
    if code == grpc.StatusCode.UNAVAILABLE and ("SSL_ERROR_SSL" in details or
                                                "Ssl handshake failed" in details):
        return TlsError(f"TLS handshake with server {server} failed ({details}): check tls_ca, "
                        "the server's certificate names, and tls_cert/tls_key if the server asks "
                        "for client certificates", code)
    if code == grpc.StatusCode.UNAVAILABLE and not tls and "Socket closed" in details:
        # Unavailable still: a server going down closes connections too, and that is retried.
        return Unavailable(f"server {server} closed the connection before answering: it speaks "
                           "TLS, most likely (a TLS server closes plain-text connections so); "
                           f"give the CA of its certificate as tls_ca ({details})", code)
    if code == grpc.StatusCode.UNAVAILABLE:
        return Unavailable(f"server {server} not reachable: {details}", code)
    return _BY_CODE.get(code, LightfarmError)(details, code)
