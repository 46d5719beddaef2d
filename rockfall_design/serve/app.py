"""The ASGI application of ``rockfall-design serve``: the page, its assets and the API.

Every request must carry the run's token: in the address the command
prints (``?token=...``); the page holds it and sends it in the
``X-Rockfall-Token`` header (no cookie: a cookie of 127.0.0.1 goes to every
port, to other servers of this app and to other local services). A
request that changes something must also come from the app's own page (its
``Origin``, or lacking one a same-origin ``Referer``) as
``application/json``. Anything else gets 403, so other local users and
other pages (another port of 127.0.0.1 too) cannot use the app.

API (JSON; an error is ``{"error": "one line"}`` with a 4xx or 5xx status
and changes nothing):

==========================================  ==========================================
``GET  /api/projects``                      the projects served
``GET  /api/projects/{id}``                 section, releases, stations, protected
                                            zone, measures, latest run and job
``POST /api/projects/{id}/simulate``        start a run ``{"rocks", "seed"}``: a job
``GET  /api/jobs/{job}``                    its progress
``POST /api/jobs/{job}/cancel``             stop it
``GET  /api/projects/{id}/run``             envelopes, stops and paths of the last run
``POST /api/projects/{id}/check``           ``{"measures", "rocks", "seed"}``: a job whose
                                            result is ``check --json``
``POST /api/projects/{id}/optimise``        ``{"rocks", "seed"}``: a job whose result is
                                            ``optimise --json``
``POST /api/projects/{id}/study``           ``{"rocks", "seed"}``: a job whose result is
                                            ``study --json``, with ``tables``
``POST /api/projects/{id}/calibrate``       ``{"rocks", "seed", "bootstrap"}``: a job
                                            whose result is ``calibrate --json``
``GET  /api/jobs/{job}/files/design.yaml``  the chosen design, as ``--out`` writes it
``GET  /api/jobs/{job}/files/report.html``  a check's or optimise's report, as
                                            ``--report`` writes it
``GET  /api/jobs/{job}/files/NAME.png``     its figures (``.svg`` too; the job lists
                                            them in ``files``)
``POST /api/place``                         ``{"project", "measure", "x"}`` or
                                            ``{"project", "measures": [...]}``: checks,
                                            bounds and residual from the run's table
``GET  /api/plugins``                       ``plugins --json``: measures and their
                                            parameters, for the forms
``GET  /api/projects/{id}/file``            the project file's text and ``version``
``POST /api/projects/{id}/validate``        ``{"text"}``: the command line's one-line
                                            error, or ok
``POST /api/projects/{id}/save``            ``{"text", "version"}``: write the project
                                            file, only if unchanged since read
``POST /api/projects/{id}/upload``          ``{"path", "text", "replace"}``: import a
                                            section, stops or a library there
``GET  /api/projects/{id}/materials``       the entries of its materials library
                                            (``?path=FILE``: another one), law, values
``POST /api/projects/{id}/materials``       ``{"segment", "material", "library"}``: give
                                            a segment that material, in memory only
==========================================  ==========================================
"""

from __future__ import annotations

import html
import json
import math
import secrets
from collections.abc import Sequence
from importlib import resources
from typing import Any
from urllib.parse import parse_qs, quote

from starlette.applications import Starlette
from starlette.concurrency import run_in_threadpool
from starlette.exceptions import HTTPException
from starlette.requests import Request
from starlette.responses import FileResponse, HTMLResponse, JSONResponse, Response
from starlette.routing import Route

from ..plugins import plugins_json
from .guards import (
    MAX_BODY_BYTES,
    ServeError,
    inside,
    non_finite_key,
    request_problem,
    version_of,
)
from .jobs import JobStore
from .reports import media_type
from .workbench import ProjectEntry

#: Header that carries the token on every request of the page (and of a script).
TOKEN_HEADER = "X-Rockfall-Token"

_STATIC_FILES = {"app.js": "text/javascript", "style.css": "text/css",
                 "index.html": "text/html"}


# The page loads nothing but this app's own files (no CDN, no inline script),
# may not be framed by another site, and is not kept in a cache.
_PAGE_HEADERS = {
    "Cache-Control": "no-store",
    "Content-Security-Policy": "default-src 'self'; img-src 'self' data:; "
                               "style-src 'self' 'unsafe-inline'; frame-ancestors 'none'",
    "X-Content-Type-Options": "nosniff",
    "Referrer-Policy": "no-referrer",
}


def _refusal(status: int, message: str) -> JSONResponse:
    return JSONResponse({"error": message}, status_code=status,
                        headers={"Cache-Control": "no-store"})


class TokenGuard:
    """ASGI middleware: the token on every request, and only the app's page changes anything.

    The token comes in the :data:`TOKEN_HEADER` header (the page holds it
    and sends it with every request) or the ``token`` query parameter (the
    printed address, the page's assets and downloads). No cookie: a cookie
    of 127.0.0.1 goes to every port of it, to another server of this app and
    to any other local service. A request that is not a GET or HEAD must
    also come from the app's own origin as JSON
    (:func:`~rockfall_design.serve.guards.request_problem`). Everything
    refused is 403 with a JSON error; an exception that escapes an endpoint
    is answered 500 with one line, never a traceback on the terminal.
    """

    def __init__(self, app: Any, token: str) -> None:
        self.app = app
        self.token = token

    def _problem(self, scope: dict) -> str | None:
        headers = {k.decode("latin-1").lower(): v.decode("latin-1")
                   for k, v in scope.get("headers", [])}
        query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
        given = headers.get(TOKEN_HEADER.lower()) or query.get("token", [""])[0]
        if not (given and secrets.compare_digest(given.encode(), self.token.encode())):
            return ("this address needs the token that rockfall-design serve printed "
                    "(open the address it printed)")
        return request_problem(scope.get("method", "GET"), scope.get("scheme", "http"),
                               headers)

    async def __call__(self, scope: dict, receive: Any, send: Any) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        problem = self._problem(scope)
        if problem is not None:
            await _refusal(403, problem)(scope, receive, send)
            return
        started = False

        async def tracked(message: dict) -> None:
            nonlocal started
            started = started or message["type"] == "http.response.start"
            await send(message)

        try:
            await self.app(scope, receive, tracked)
        except Exception as exc:  # noqa: BLE001 -- one line to the page, no traceback
            if not started:
                await _refusal(500, _one_line(exc))(scope, receive, send)


def _one_line(exc: BaseException) -> str:
    """An unexpected error as one line: its type and message, no traceback."""
    text = " ".join(str(exc).split())
    return f"internal error: {type(exc).__name__}{': ' + text if text else ''}"


def _error(exc: ServeError) -> JSONResponse:
    return JSONResponse({"error": exc.message}, status_code=exc.status)


def _clean(v: Any) -> Any:
    """JSON-safe: NaN and infinities become null (JSON has neither)."""
    if isinstance(v, float):
        return v if math.isfinite(v) else None
    if isinstance(v, dict):
        return {k: _clean(x) for k, x in v.items()}
    if isinstance(v, list | tuple):
        return [_clean(x) for x in v]
    return v


def _json(data: Any, status: int = 200) -> JSONResponse:
    return JSONResponse(_clean(data), status_code=status)


async def _body(request: Request) -> dict[str, Any]:
    """The request's JSON object, refused when too large or not an object.

    Raises
    ------
    ServeError
        413 above :data:`MAX_BODY_BYTES`; 400 for a body that is not a JSON object.
    """
    declared = request.headers.get("content-length")
    if declared is not None:
        try:
            if int(declared) > MAX_BODY_BYTES:
                raise ServeError(413, f"request body of {int(declared):,} bytes is larger than "
                                 f"the {MAX_BODY_BYTES:,} bytes allowed")
        except ValueError:
            raise ServeError(400, "malformed Content-Length header") from None
    chunks, size = [], 0
    async for chunk in request.stream():
        size += len(chunk)
        if size > MAX_BODY_BYTES:
            raise ServeError(413, f"request body is larger than the {MAX_BODY_BYTES:,} bytes "
                             "allowed")
        chunks.append(chunk)
    raw = b"".join(chunks)
    if not raw:
        return {}
    try:
        data = json.loads(raw)
    except (ValueError, UnicodeDecodeError) as exc:
        raise ServeError(400, f"malformed JSON body: {exc}") from None
    if not isinstance(data, dict):
        raise ServeError(400, "expected a JSON object as the request body")
    bad = non_finite_key(data)
    if bad is not None:
        raise ServeError(400, f"{bad}: expected a finite number (NaN, Infinity and numbers "
                         "beyond 1.8e308 are not numbers the app can use)")
    return data


def _optional_int(data: dict[str, Any], key: str) -> int | None:
    v = data.get(key)
    if v is None:
        return None
    if (isinstance(v, bool) or not isinstance(v, int | float)
            or (isinstance(v, float) and not (math.isfinite(v) and v.is_integer()))):
        raise ServeError(400, f"{key}: expected a whole number, got {_short(v)}")
    if abs(v) > _LARGEST_WHOLE:
        raise ServeError(400, f"{key}: {_short(v)} is beyond any number of rocks or seed "
                         f"the app takes (at most {_LARGEST_WHOLE:.3g})")
    return int(v)


#: Largest whole number a request may give (rocks, seed, bootstrap): 2**63 - 1,
#: the engine's integers; the endpoints' own bounds are far below for rocks.
_LARGEST_WHOLE = 2**63 - 1


def _short(v: Any) -> str:
    """A value for a message, cut to 40 characters."""
    text = repr(v)
    return text if len(text) <= 40 else text[:37] + "..."


def _handle(fn: Any) -> Any:
    """An endpoint that answers a ServeError with its status and message."""
    async def endpoint(request: Request) -> Response:
        try:
            return await fn(request)
        except ServeError as exc:
            return _error(exc)
        except Exception as exc:  # noqa: BLE001 -- one line to the page, no traceback
            return _refusal(500, _one_line(exc))
    return endpoint


class _Endpoints:
    """The app's endpoints over the served projects and their jobs (one per app)."""

    def __init__(self, entries: Sequence[ProjectEntry], token: str) -> None:
        self.entries = list(entries)
        self.by_id = {e.id: e for e in self.entries}
        self.jobs = JobStore()
        self.token = token

    def entry_of(self, request: Request) -> ProjectEntry:
        """The served project a request's path names (``/api/projects/{pid}/...``)."""
        return self.entry(request.path_params["pid"])

    def entry(self, pid: str) -> ProjectEntry:
        """The served project of id ``pid``; a 404 naming the served ones where none is."""
        e = self.by_id.get(pid)
        if e is None:
            known = ", ".join(self.by_id) or "none"
            raise ServeError(404, f"unknown project {pid!r} (served: {known})")
        return e

    async def page(self, request: Request) -> Response:
        return _page(self.token)

    async def static(self, request: Request) -> Response:
        name = request.path_params["name"]
        if name not in _STATIC_FILES:
            raise ServeError(404, f"no asset {name!r}")
        return _static(name)

    async def projects(self, request: Request) -> Response:
        return _json({"projects": [{"id": e.id, "name": e.project.name, "file": e.path.name}
                                   for e in self.entries]})

    async def project(self, request: Request) -> Response:
        return _json(self.entry_of(request).describe())

    async def run(self, request: Request) -> Response:
        e = self.entry_of(request)
        if e.run is None:
            raise ServeError(409, f"{e.id} has not been simulated yet (POST .../simulate)")
        return _json(e.run_dict())

    async def simulate(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        job = e.start_run(_optional_int(data, "rocks"), _optional_int(data, "seed"))
        self.jobs.add(job)
        return _json(job.as_dict(), 202)

    async def check(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        raws = data.get("measures")
        if raws is not None and not isinstance(raws, list):
            raise ServeError(400, "measures: expected a list of measures")
        job = e.start_check(raws, _optional_int(data, "rocks"), _optional_int(data, "seed"))
        self.jobs.add(job)
        return _json(job.as_dict(), 202)

    async def optimise(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        job = e.start_optimise(_optional_int(data, "rocks"), _optional_int(data, "seed"))
        self.jobs.add(job)
        return _json(job.as_dict(), 202)

    async def study(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        job = e.start_study(_optional_int(data, "rocks"), _optional_int(data, "seed"))
        self.jobs.add(job)
        return _json(job.as_dict(), 202)

    async def calibrate(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        job = e.start_calibrate(_optional_int(data, "rocks"), _optional_int(data, "seed"),
                                _optional_int(data, "bootstrap"))
        self.jobs.add(job)
        return _json(job.as_dict(), 202)

    async def job_file(self, request: Request) -> Response:
        j = self.job_of(request)
        name = request.path_params["name"]
        if name not in j.files:
            if name in j.released:
                raise ServeError(410, f"job {j.id}: {name} is no longer kept (the app keeps "
                                 f"the full results of the last {self.jobs.keep_full} jobs); "
                                 "run it again")
            raise ServeError(404, f"job {j.id} has no {name}")
        self.jobs.touch(j)
        content = j.files[name]
        if callable(content):
            # The report and figures are drawn on the first request (seconds):
            # in a worker thread, so that the page's other requests go on.
            try:
                content = await run_in_threadpool(content)
            except Exception as exc:  # noqa: BLE001 -- one line to the page, the app stays up
                raise ServeError(500, f"{name}: {' '.join(str(exc).split())}") from None
        return Response(content, media_type=media_type(name),
                        headers={"Content-Disposition": f'attachment; filename="{name}"'})

    def job_of(self, request: Request) -> Any:
        jid = request.path_params["jid"]
        job = self.jobs.get(jid)
        if job is None:  # never started, or forgotten (the app keeps the latest jobs)
            raise ServeError(404, f"unknown job {jid!r}")
        return job

    async def job(self, request: Request) -> Response:
        return _json(self.job_of(request).as_dict())

    async def cancel(self, request: Request) -> Response:
        j = self.job_of(request)
        j.cancel_event.set()
        return _json(j.as_dict())

    async def place(self, request: Request) -> Response:
        data = await _body(request)
        pid = data.get("project")
        if not isinstance(pid, str):
            raise ServeError(400, "project: expected the id of a served project")
        e = self.entry(pid)
        if "measures" in data:
            raws = data["measures"]
            if not isinstance(raws, list) or not raws:
                raise ServeError(400, "measures: expected a non-empty list of measures")
        else:
            m = data.get("measure")
            if not isinstance(m, dict):
                raise ServeError(400, "measure: expected an object such as "
                                 '{"type": "fence", "height": 5, "capacity_kj": 2000}')
            x = data.get("x", m.get("x"))
            if isinstance(x, bool) or not isinstance(x, int | float) or not math.isfinite(x):
                raise ServeError(400, f"x: expected the station in m, got {x!r}")
            raws = [{**m, "x": float(x)}]
        run = e.run
        if run is None:
            raise ServeError(409, f"{e.id} has not been simulated yet (POST "
                             f"/api/projects/{e.id}/simulate first)")
        # A few milliseconds of numpy: run here, on the event loop, for the
        # lowest latency while the mouse moves.
        return _json(run.place(e, raws))

    async def plugins(self, request: Request) -> Response:
        reg = self.entries[0].registry if self.entries else None
        if reg is None:
            raise ServeError(404, "no project served")
        return _json(plugins_json(reg))

    async def file(self, request: Request) -> Response:
        e = self.entry_of(request)
        name = request.query_params.get("path", e.path.name)
        target = _inside(e, name)
        if not target.is_file():
            raise ServeError(404, f"no file {name!r} in the project's directory")
        if target.stat().st_size > MAX_BODY_BYTES:
            raise ServeError(413, f"{name}: larger than {MAX_BODY_BYTES:,} bytes")
        try:
            text = target.read_text(encoding="utf-8")
        except UnicodeDecodeError:
            raise ServeError(400, f"{name}: not a UTF-8 text file") from None
        # Save sends the version back: it writes only over the file the page read.
        version = version_of(target)
        return JSONResponse(_clean({"path": name, "text": text, "version": version}),
                            headers={"ETag": f'"{version}"'})

    async def validate(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        e.validate(data.get("text"))
        return _json({"ok": True})

    async def save(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        name = data.get("path")
        if name is not None and name != e.path.name:
            # The path is the project's: Save never writes another file.
            raise ServeError(400, f"path: Save writes the project file it opened "
                             f"({e.path.name}) and nothing else; leave path out")
        target = await run_in_threadpool(e.save, data.get("text"), data.get("version"))
        return _json({"ok": True, "path": str(target.relative_to(e.directory)),
                      "version": version_of(target)})

    async def materials(self, request: Request) -> Response:
        e = self.entry_of(request)
        return _json(e.library(request.query_params.get("path")))

    async def apply_material(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        name, library = data.get("material"), data.get("library")
        if not isinstance(name, str):
            raise ServeError(400, "material: expected the name of a library entry")
        if library is not None and not isinstance(library, str):
            raise ServeError(400, "library: expected a file name inside the project's directory")
        return _json(e.apply_material(data.get("segment"), name, library))

    async def upload(self, request: Request) -> Response:
        e = self.entry_of(request)
        data = await _body(request)
        name = data.get("path")
        if not isinstance(name, str):
            raise ServeError(400, "path: expected a file name inside the project's directory")
        target = await run_in_threadpool(e.upload, name, data.get("text"),
                                         data.get("replace", False) is True)
        return _json({"ok": True, "path": str(target.relative_to(e.directory))})


def create_app(entries: Sequence[ProjectEntry], token: str | None = None) -> Any:
    """The app serving ``entries``, guarded by ``token`` (a new random one if None).

    Returns the ASGI application; its token is ``app.state.token`` of the
    inner Starlette app, also as the attribute ``token`` of the returned object.
    """
    token = token or secrets.token_urlsafe(24)
    ep = _Endpoints(entries, token)

    routes = [
        Route("/", _handle(ep.page)),
        Route("/static/{name}", _handle(ep.static)),
        Route("/api/projects", _handle(ep.projects)),
        Route("/api/projects/{pid}", _handle(ep.project)),
        Route("/api/projects/{pid}/run", _handle(ep.run)),
        Route("/api/projects/{pid}/simulate", _handle(ep.simulate), methods=["POST"]),
        Route("/api/projects/{pid}/file", _handle(ep.file)),
        Route("/api/projects/{pid}/validate", _handle(ep.validate), methods=["POST"]),
        Route("/api/projects/{pid}/save", _handle(ep.save), methods=["POST"]),
        Route("/api/projects/{pid}/upload", _handle(ep.upload), methods=["POST"]),
        Route("/api/projects/{pid}/materials", _handle(ep.materials)),
        Route("/api/projects/{pid}/materials", _handle(ep.apply_material), methods=["POST"]),
        Route("/api/projects/{pid}/check", _handle(ep.check), methods=["POST"]),
        Route("/api/projects/{pid}/optimise", _handle(ep.optimise), methods=["POST"]),
        Route("/api/projects/{pid}/study", _handle(ep.study), methods=["POST"]),
        Route("/api/projects/{pid}/calibrate", _handle(ep.calibrate), methods=["POST"]),
        Route("/api/jobs/{jid}", _handle(ep.job)),
        Route("/api/jobs/{jid}/files/{name}", _handle(ep.job_file)),
        Route("/api/jobs/{jid}/cancel", _handle(ep.cancel), methods=["POST"]),
        Route("/api/place", _handle(ep.place), methods=["POST"]),
        Route("/api/plugins", _handle(ep.plugins)),
    ]
    inner = Starlette(routes=routes, exception_handlers={HTTPException: _http_error})
    inner.state.token = token
    inner.state.entries = ep.entries
    app = TokenGuard(inner, token)
    app.state = inner.state  # type: ignore[attr-defined]
    return app


async def _http_error(request: Request, exc: Exception) -> Response:
    """Starlette's own refusals (no such route, method not allowed) as JSON errors too."""
    status = getattr(exc, "status_code", 500)
    detail = getattr(exc, "detail", "") or "error"
    return _refusal(status, f"{request.method} {request.url.path}: {detail}")


def _page(token: str) -> Response:
    """The page with the token it sends with every request (in a meta tag and asset links)."""
    path = resources.files("rockfall_design.serve").joinpath("static", "index.html")
    text = path.read_text(encoding="utf-8")
    text = text.replace("__TOKEN_QUERY__", quote(token, safe=""))
    text = text.replace("__TOKEN__", html.escape(token, quote=True))
    return HTMLResponse(text, headers=_PAGE_HEADERS)


def _inside(e: ProjectEntry, name: str) -> Any:
    return inside(e.directory, name)


def _static(name: str) -> Response:
    path = resources.files("rockfall_design.serve").joinpath("static", name)
    with resources.as_file(path) as p:
        return FileResponse(p, media_type=_STATIC_FILES[name], headers=_PAGE_HEADERS)
