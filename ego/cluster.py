"""Joining a Ray cluster: the address checked first, Ray's failures in one line.

``ray.init(address=...)`` retries an address where nothing listens for minutes, printing
Ray's log, and a cluster that refuses the connection raises a ``ConnectionError`` with a
traceback. :func:`check_address` tries a plain TCP connection first (a few seconds at most)
and :func:`joining` turns whatever ``ray.init`` raises into a ConfigError naming the address
and the cause, so ``ego sweep --engine ray --address HOST:PORT`` answers in one line within
seconds.

:func:`start_local_ray` starts a private Ray instance whose processes end with this process:
Ray's own dashboard and runtime-env agents otherwise outlive a SIGKILLed driver.
"""

from __future__ import annotations

import os
import socket
from contextlib import contextmanager

from ego.params import ConfigError

#: how long a TCP connection to the address may take before it is called unreachable
CONNECT_TIMEOUT = 5.0
#: Ray's own bound on reaching the cluster's GCS (seconds)
GCS_TIMEOUT = 10


def _host_port(address: str) -> tuple[str, int] | None:
    """(host, port) of ``host:port`` or ``ray://host:port``; None for ``auto``/``local``."""
    text = address.strip()
    if text in ("auto", "local", ""):
        return None
    if "://" in text:
        scheme, _, text = text.partition("://")
        if scheme != "ray":
            raise ConfigError(f"bad --address {address!r} (expected host:port, ray://host:port or auto)")
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
        raise ConfigError(f"bad --address {address!r} (expected host:port, ray://host:port or auto)")
    return host.strip("[]"), int(port)


def check_address(address: str) -> None:
    """ConfigError unless something accepts a TCP connection at ``address`` within
    :data:`CONNECT_TIMEOUT` seconds (``auto`` is left to Ray)."""
    if not isinstance(address, str):
        raise ConfigError(f"bad --address {address!r} (expected host:port, ray://host:port or auto)")
    target = _host_port(address)
    if target is None:
        return
    try:
        with socket.create_connection(target, timeout=CONNECT_TIMEOUT) as sock:
            speaks_grpc = _answers_http2(sock)
    except socket.gaierror as exc:
        raise ConfigError(f"cannot join the Ray cluster at {address!r}: unknown host ({exc.strerror})") from None
    except TimeoutError:
        raise ConfigError(
            f"cannot join the Ray cluster at {address!r}: no answer within {CONNECT_TIMEOUT:g} s"
        ) from None
    except OSError as exc:
        raise ConfigError(
            f"cannot join the Ray cluster at {address!r}: {exc.strerror or exc} (is a Ray head running there?)"
        ) from None
    if not speaks_grpc:
        raise ConfigError(
            f"cannot join the Ray cluster at {address!r}: something listens there but it "
            "is not a Ray head (it does not speak gRPC)"
        )


#: an HTTP/2 client's first bytes: the connection preface and an empty SETTINGS frame
_PREFACE = b"PRI * HTTP/2.0\r\n\r\nSM\r\n\r\n" + bytes([0, 0, 0, 4, 0, 0, 0, 0, 0])


def _answers_http2(sock: socket.socket) -> bool:
    """A Ray head's GCS (and a Ray client server) is a gRPC server: it answers an HTTP/2
    preface with a SETTINGS frame. Anything else listening there (a web server) does not,
    and ``ray.init`` would wait on it for minutes."""
    try:
        sock.sendall(_PREFACE)
        head = b""
        while len(head) < 9:
            chunk = sock.recv(9 - len(head))
            if not chunk:
                return False
            head += chunk
    except OSError:
        return False
    return head[3] == 4  # the frame type: SETTINGS


@contextmanager
def joining(address: str):
    """Ray's failures to connect as one ConfigError naming ``address`` and the cause."""
    target = _host_port(address) if isinstance(address, str) else None
    if target is not None and _loopback(target[0]):
        _stay_on_loopback()
    try:
        yield
    except ConfigError:
        raise
    except (ConnectionError, TimeoutError, RuntimeError, ValueError, OSError) as exc:
        _shutdown_quietly()
        cause = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ConfigError(f"cannot join the Ray cluster at {address!r}: {cause[:200]}") from None
    except Exception as exc:  # noqa: BLE001 - Ray's own exception types vary by version
        _shutdown_quietly()
        cause = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        raise ConfigError(
            f"cannot join the Ray cluster at {address!r}: {type(exc).__name__}" + (f": {cause[:200]}" if cause else "")
        ) from None


def _loopback(host: str) -> bool:
    import ipaddress

    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def _stay_on_loopback() -> None:
    """A cluster on 127.0.0.1 (``ray.cluster_utils.Cluster``, a head started with
    ``--node-ip-address 127.0.0.1``): Ray would replace the loopback address by this
    machine's outward address before connecting, where the cluster does not listen, and
    retry for minutes. Ray's own switch for single-machine clusters keeps it on loopback."""
    try:
        import ray._private.ray_constants as constants

        constants.ENABLE_RAY_CLUSTER = False
    except (ImportError, AttributeError):
        pass


def _shutdown_quietly() -> None:
    try:
        import ray

        if ray.is_initialized():
            ray.shutdown()
    except Exception:  # noqa: BLE001, S110 - a failed join is being reported already
        pass


def reap_with_this_process() -> None:
    """Make every process this one has started so far (and any they start) end when this
    one ends, however it ends: a watcher process kills them. For a private Ray instance,
    whose agents (``ray::DashboardAgent``, ``ray::RuntimeEnvAgent``) outlive a SIGKILLed
    driver otherwise."""
    from ego.reaper import start_reaper

    start_reaper(os.getpid())
