"""The channel a PathdClient talks over: plaintext or TLS (mutual TLS with a
client certificate), and a bearer token on every call, as pathctl's --tls_ca,
--tls_cert, --tls_key, --tls_server_name, --token and --token_file make it
(client/client.h, LoadClientCredentials and MakeChannel)."""

from __future__ import annotations

import collections
import os
from typing import Union

import grpc

# Whole maps (GetMap with cells) and cost-to-go fields exceed gRPC's default
# 4 MiB receive limit; the server bounds what it sends (--max_message_bytes).
_CHANNEL_OPTIONS = (("grpc.max_receive_message_length", -1),
                    ("grpc.max_send_message_length", -1))

PemSource = Union[str, os.PathLike, bytes]


def _pem(what: str, source: PemSource | None) -> bytes | None:
    """PEM bytes given directly, or read from the file a path names."""
    if source is None or isinstance(source, bytes):
        return source
    try:
        with open(source, "rb") as f:
            return f.read()
    except OSError as error:
        raise ValueError(f"{what}: cannot read {os.fspath(source)}: {error.strerror}") from None


def _checked_token(token: str | None, token_file: str | os.PathLike | None) -> str | None:
    if token is not None and token_file is not None:
        raise ValueError("give token or token_file, not both")
    what = "token"
    if token_file is not None:
        what = "token_file"
        try:
            with open(token_file, encoding="ascii", errors="replace") as f:
                token = f.read().strip()
        except OSError as error:
            raise ValueError(f"token_file: cannot read {os.fspath(token_file)}: "
                             f"{error.strerror}") from None
        if not token:
            raise ValueError(f"token_file: {os.fspath(token_file)} is empty")
    if token is None:
        return None
    # Visible ASCII only: what a Bearer token in an HTTP/2 header can hold.
    # The message describes the token without quoting it.
    if not token or not all(0x21 <= ord(c) <= 0x7e for c in token):
        raise ValueError(f"{what}: a token may hold only visible ASCII characters "
                         "(no spaces or line breaks inside)")
    return token


class _CallDetails(collections.namedtuple(
        "_CallDetails", ("method", "timeout", "metadata", "credentials",
                         "wait_for_ready", "compression")),
        grpc.ClientCallDetails):
    pass


class _BearerToken(grpc.UnaryUnaryClientInterceptor, grpc.UnaryStreamClientInterceptor,
                   grpc.StreamUnaryClientInterceptor, grpc.StreamStreamClientInterceptor):
    """Adds "authorization: Bearer <token>" to every call, streams included.
    An interceptor rather than grpc's call credentials, which grpc refuses
    to send over a plaintext channel; pathd accepts tokens on both (on
    loopback a plaintext token never crosses a network)."""

    def __init__(self, token: str):
        self._header = ("authorization", f"Bearer {token}")

    def _details(self, details):
        metadata = list(details.metadata or ()) + [self._header]
        return _CallDetails(details.method, details.timeout, metadata,
                            details.credentials, getattr(details, "wait_for_ready", None),
                            getattr(details, "compression", None))

    def intercept_unary_unary(self, continuation, details, request):
        return continuation(self._details(details), request)

    def intercept_unary_stream(self, continuation, details, request):
        return continuation(self._details(details), request)

    def intercept_stream_unary(self, continuation, details, request_iterator):
        return continuation(self._details(details), request_iterator)

    def intercept_stream_stream(self, continuation, details, request_iterator):
        return continuation(self._details(details), request_iterator)


def make_channel(address: str, *, tls_ca: PemSource | None = None,
                 tls_cert: PemSource | None = None, tls_key: PemSource | None = None,
                 tls_server_name: str | None = None, token: str | None = None,
                 token_file: str | os.PathLike | None = None) -> grpc.Channel:
    """A channel to pathd at `address` ("host:port" or a gRPC target URI).

    tls_ca turns TLS on: the CA certificate(s) the server's certificate must
    chain to, PEM bytes or a file path. tls_cert and tls_key (both or
    neither) are the client's certificate chain and key for a server with
    --tls_client_ca. tls_server_name is the name the server's certificate
    must carry when the address's host is not it. token (or token_file, one
    line holding it) is sent as a bearer token on every call. Raises
    ValueError naming the argument for a file that cannot be read or a
    combination that makes no sense.
    """
    if (tls_cert is None) != (tls_key is None):
        raise ValueError("give tls_cert and tls_key together (mutual TLS), or neither")
    if tls_ca is None and (tls_cert is not None or tls_server_name):
        raise ValueError("tls_cert, tls_key and tls_server_name need tls_ca (TLS)")
    header_token = _checked_token(token, token_file)
    options = list(_CHANNEL_OPTIONS)
    if tls_ca is not None:
        credentials = grpc.ssl_channel_credentials(
            root_certificates=_pem("tls_ca", tls_ca),
            private_key=_pem("tls_key", tls_key),
            certificate_chain=_pem("tls_cert", tls_cert))
        if tls_server_name:
            options.append(("grpc.ssl_target_name_override", tls_server_name))
        channel = grpc.secure_channel(address, credentials, options=options)
    else:
        channel = grpc.insecure_channel(address, options=options)
    if header_token is not None:
        channel = grpc.intercept_channel(channel, _BearerToken(header_token))
    return channel
