"""``rockfall-design serve``: design in the browser (needs the ``web`` extra).

The page draws the section to scale, runs the project's rocks once on the
bare slope with a progress bar and cancel, and shows the envelopes of
passing height and energy and where rocks stop. A fence or wall dragged
along the slope is judged from that run's per-rock table of passing height
and energy at every metre, through the optimiser's screening and the
project's safety concept, so its checks and the residual at the protected
zone follow the mouse without running a rock again.

- :mod:`.app`: the ASGI application, the page, its assets and the API;
- :mod:`.workbench`: what the app works on: the projects, their runs and
  the measures placed on the table;
- :mod:`.page_run`: :class:`~.page_run.PageRun`, one finished run of the
  page (the trial run's table, the envelopes, the stops and the paths the
  page draws) and the judgement of measures placed on it;
- :mod:`.jobs` and :mod:`.job_tables`: the jobs a page starts (a run, a
  check, an optimisation, a study, a calibration) and their tables;
- :mod:`.reports`: the report and figures of a check or optimise;
- :mod:`.guards`: which files a page may read and write.

Import :func:`serve` lazily: it needs Starlette and uvicorn
(``pip install "rockfall-design[web]"``).
"""

from __future__ import annotations

import asyncio
import errno
import secrets
import socket
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import TextIO

from ..errors import InputError, RockfallError
from ..plugins import load_registry

__all__ = ["serve", "DEFAULT_PORT", "find_projects"]

#: Port tried first; the next ones are tried when it is taken.
DEFAULT_PORT = 8765
_PORT_TRIES = 20


def _needs_web() -> None:
    try:
        import starlette  # noqa: F401
        import uvicorn  # noqa: F401
    except ImportError as exc:
        raise InputError(
            f"serve needs the web extra ({exc.name} is not installed): "
            'pip install "rockfall-design[web]"') from None


def find_projects(directory: Path) -> list[Path]:
    """The project files (``*.yaml`` with a ``slope:`` key at the top) of a directory."""
    out = []
    for p in sorted(directory.glob("*.yaml")):
        try:
            head = p.read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        if any(line.startswith("slope:") for line in head.splitlines()):
            out.append(p)
    return out


def _bind(host: str, port: int | None) -> socket.socket:
    """A listening socket on ``host``: ``port``, or the first free one from DEFAULT_PORT."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    tries = [port] if port is not None else [DEFAULT_PORT + i for i in range(_PORT_TRIES)]
    last: OSError | None = None
    for p in tries:
        # IPPROTO_TCP said explicitly: asyncio sets TCP_NODELAY only on sockets
        # that say so, and without it a response in two writes waits for the
        # browser's delayed ACK (40 ms per request).
        sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            sock.bind((host, p))
        except OSError as exc:
            sock.close()
            last = exc
            if exc.errno != errno.EADDRINUSE:
                break
            continue
        sock.listen(128)
        sock.set_inheritable(True)
        return sock
    what = f"port {port}" if port is not None else (
        f"ports {DEFAULT_PORT} to {DEFAULT_PORT + _PORT_TRIES - 1}")
    raise InputError(f"cannot listen on {host}, {what}: {last.strerror if last else 'busy'} "
                     "(choose another with --port)")


def serve(paths: Sequence[Path], *, host: str = "127.0.0.1", port: int | None = None,
          block: Sequence[str] = (), out: TextIO | None = None,
          token: str | None = None) -> int:
    """Serve the projects until interrupted; print the address with its token first.

    Parameters
    ----------
    paths
        Project files; none: the project files of the current directory.
    host
        Address to listen on (default: this machine only).
    port
        Port; None: the first free one from :data:`DEFAULT_PORT`.
    block
        Plugin names not to load (as ``--block``).
    out
        Where the address is printed (default: stdout).
    token
        The token of the address (default: a new random one).

    Returns
    -------
    int
        0 after a clean shutdown.

    Raises
    ------
    InputError
        The web extra is missing, no project was given or found, or the
        port cannot be bound.
    ProjectError
        A project file is not valid.
    """
    _needs_web()
    # The web extra (uvicorn, starlette) is optional: the app's modules import it
    # at their top, so they are imported once _needs_web() has found it.
    import uvicorn

    from .app import create_app
    from .workbench import load_entries

    registry = load_registry(blocked=tuple(block))
    for f in registry.failures:
        sys.stderr.write(f"rockfall-design serve: plugin {f.plugin!r} was not loaded: "
                         f"{f.reason}\n")
    if paths:
        entries = load_entries([Path(p) for p in paths], registry)
    else:
        # Found, not named: a file that is not a valid project is left out, and said so.
        entries = []
        for p in find_projects(Path.cwd()):
            try:
                entries += load_entries([p], registry)
            except RockfallError as exc:
                sys.stderr.write(f"rockfall-design serve: left out: {exc}\n")
    if not entries:
        raise InputError("serve: no project file given and none in the current directory "
                         "(rockfall-design serve projects/design_two_zones.yaml)")
    token = token or secrets.token_urlsafe(24)
    app = create_app(entries, token)
    sock = _bind(host, port)
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{sock.getsockname()[1]}/?token={token}"
    stream = out or sys.stdout
    stream.write(f"rockfall-design serve: {len(entries)} project(s) at\n    {url}\n"
                 "open it in a browser; Ctrl-C stops the server\n")
    stream.flush()
    config = uvicorn.Config(app, log_level="warning", lifespan="off")
    server = uvicorn.Server(config)
    try:
        asyncio.run(server.serve(sockets=[sock]))
    except KeyboardInterrupt:
        # uvicorn shuts down on Ctrl-C, then raises the signal again: the
        # server was stopped as asked, and it writes no files of its own.
        pass
    finally:
        sock.close()
    stream.write("rockfall-design serve: stopped\n")
    return 0
