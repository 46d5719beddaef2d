"""A --scheduler that is not a Dask scheduler fails fast, in one line (issue 27, item 7).

A service that accepts and never answers used to hang with no output; one
that sends a banner (SSH, HTTP) ended in a traceback allocating exabytes.
Now: connect, handshake and answer within SCHEDULER_TIMEOUT_S, or one line
naming the address, exit code 2.
"""

from __future__ import annotations

import socket
import threading
import time
from pathlib import Path

import pytest

from rockfall_design.cli.program import main
from rockfall_design.errors import InputError
from rockfall_design.studies import executors

ROOT = Path(__file__).resolve().parents[2]
TALUS = ROOT / "projects" / "study_talus.yaml"


class _Silent:
    """A client class whose connection never completes."""

    def __init__(self, address: str, timeout: str) -> None:
        time.sleep(30)

    def close(self) -> None:
        """Closed by the connecting thread when it answers after the wait gave up."""


class _Garbled:
    """A client class that reads a banner as a Dask frame length."""

    def __init__(self, address: str, timeout: str) -> None:
        raise MemoryError("Unable to allocate 2.82 EiB for an array")


def test_a_silent_peer_is_one_line_within_the_timeout(monkeypatch):
    monkeypatch.setattr(executors, "SCHEDULER_TIMEOUT_S", 0.2)
    with pytest.raises(InputError, match=r"the Dask scheduler at tcp://10\.0\.0\.1:8786 did "
                                         r"not answer within 0\.2 s"):
        executors._connect(_Silent, "tcp://10.0.0.1:8786")


def test_a_peer_that_is_not_dask_is_one_line(monkeypatch):
    with pytest.raises(InputError, match=r"tcp://10\.0\.0\.1:80 did not answer as a Dask "
                                         r"scheduler \(MemoryError\)") as caught:
        executors._connect(_Garbled, "tcp://10.0.0.1:80")
    assert "EiB" not in str(caught.value)


@pytest.fixture
def listener():
    """A local TCP service: 'silent' accepts and never answers, 'banner' talks SSH."""
    servers = []

    def start(kind: str) -> str:
        sock = socket.socket()
        sock.bind(("127.0.0.1", 0))
        sock.listen(5)
        servers.append(sock)
        held = []

        def serve() -> None:
            while True:
                try:
                    conn, _ = sock.accept()
                except OSError:
                    return
                held.append(conn)
                if kind == "banner":
                    conn.sendall(b"SSH-2.0-OpenSSH_9.6\r\n" * 4)

        threading.Thread(target=serve, daemon=True).start()
        return f"tcp://127.0.0.1:{sock.getsockname()[1]}"

    yield start
    for sock in servers:
        sock.close()


@pytest.mark.parametrize("kind, needle", [
    ("silent", "did not answer within 1 s"),
    ("banner", "did not answer as a Dask scheduler"),
])
def test_study_with_a_wrong_scheduler_is_exit_2(listener, monkeypatch, capsys, kind, needle):
    pytest.importorskip("distributed", reason="dask.distributed (the [study] extra)")
    monkeypatch.setattr(executors, "SCHEDULER_TIMEOUT_S", 1.0)
    address = listener(kind)
    code = main(["study", str(TALUS), "--rocks", "10", "--scheduler", address])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    assert address in err and needle in err, err
