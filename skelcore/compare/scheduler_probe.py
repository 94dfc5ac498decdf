"""Whether a Dask scheduler's TCP address refuses connections, asked once before Dask connects.

Dask's ``Client`` retries a refused connection until its timeout (5 s in :mod:`.backends`), so a
mistyped port or a scheduler that is not running would cost that wait before the one-line error.
A refused TCP connection is a definite answer: one plain socket connect reports it at once
(docs/compare.md, "Backends"). Anything else (an address that is not ``tcp://HOST:PORT``,
a host that does not answer at all) is left to Dask's own connect and its timeout.
"""

from __future__ import annotations

import socket

__all__ = ["refused"]


def refused(address: str, timeout: float = 5.0) -> ConnectionRefusedError | None:
    """The refusal of a TCP connection to ``address`` (``tcp://HOST:PORT``), or None if it was not refused."""
    scheme, sep, rest = address.partition("://")
    host, _, port = rest.rpartition(":")
    if not sep or scheme != "tcp" or not host or not port.isdigit():
        return None
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=timeout).close()
    except ConnectionRefusedError as exc:
        return exc
    except OSError:
        return None
    return None
