"""Calling an API entry: validate the request, run the handler, turn refusals into error responses."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel, ValidationError

from ..agent.exceptions import ApiError
from ..text import clip
from .deferred import Deferred
from .table import ApiEntry

if TYPE_CHECKING:
    from ..sim.simulation import Simulation

log = logging.getLogger("sigcore.api")


def _validation_message(entry: ApiEntry, e: ValidationError) -> str:
    parts = []
    for err in e.errors():
        where = ".".join(str(p) for p in err["loc"]) or "request"
        parts.append(f"{where}: {err['msg']}")
    assert entry.request is not None
    fields = ", ".join(entry.request.model_fields) or "none"
    return f"invalid {entry.ros_type} request ({'; '.join(parts)}); fields: {fields}"


def call(sim: Simulation, entry: ApiEntry, agent: str,
         request: BaseModel | dict[str, Any] | None) -> dict[str, Any] | Deferred:
    """Run ``entry`` for ``agent``. Never raises for bad input.

    Returns:
        For services, every response field including ``success`` and ``message`` (what was wrong, if anything).
        For subscribed topics, ``{"success": ..., "message": ...}``. A :class:`Deferred` when the handler's answer
        needs the simulation to run on: poll it with :func:`finish` after each step.
    """
    if entry.handler is None or entry.request is None:
        return {"success": False, "message": f"{entry.suffix} is published by the simulation, not handled"}
    try:
        if isinstance(request, BaseModel) and not isinstance(request, entry.request):
            request = request.model_dump()
        req = request if isinstance(request, entry.request) else entry.request.model_validate(request or {})
        if sim.inputs.wanted:
            sim.inputs.note("api", agent=agent, entry=entry.suffix, request=req.model_dump(mode="json"))
        fields = entry.handler(sim, agent, req) or {}
        if isinstance(fields, Deferred):
            return fields
        out: dict[str, Any] = {**fields, "success": True, "message": ""}
        kind = ""
    except ValidationError as e:
        out, kind = {"success": False, "message": _validation_message(entry, e)}, "invalid request"
    except ApiError as e:
        out, kind = _refused(entry, e), type(e).__name__
    except (Exception, SystemExit) as e:  # a bug (or a feature's sys.exit) must not stop the simulation
        kind = f"internal error {type(e).__name__}"
        log.exception("handler of %s%s raised", agent, entry.suffix, extra=log_key(agent + entry.suffix, kind))
        out = {"success": False, "message": f"internal error in {entry.suffix}: {type(e).__name__}: {clip(str(e))}"}
    return _complete(entry, agent, out, kind)


def _refused(entry: ApiEntry, e: ApiError) -> dict[str, Any]:
    """The error response of a refusal: the error's fields that the response type has, ``success`` false."""
    known = entry.response.model_fields if entry.response is not None else {}
    return {**{k: v for k, v in e.fields.items() if k in known}, "success": False, "message": str(e)}


def log_key(endpoint: str, kind: str) -> dict[str, str]:
    """The ``extra=`` of a log record about a request: transports log each (endpoint, kind) once, not per text."""
    return {"endpoint": endpoint, "kind": kind}


def _complete(entry: ApiEntry, agent: str, out: dict[str, Any], kind: str) -> dict[str, Any]:
    if not out["success"]:
        log.warning("%s%s refused: %s", agent, entry.suffix, clip(out["message"]),
                    extra=log_key(agent + entry.suffix, kind))
    if entry.response is not None:
        defaults = entry.response().model_dump()
        return {**defaults, **out}
    return out


def finish(sim: Simulation, entry: ApiEntry, agent: str, deferred: Deferred) -> dict[str, Any] | None:
    """Poll a deferred response after a step: the full response once done (or failed), else ``None``."""
    try:
        fields = deferred.poll(sim.time)
        if fields is None:
            return None
        out: dict[str, Any] = {**fields, "success": True, "message": ""}
        kind = ""
    except ApiError as e:
        out, kind = _refused(entry, e), type(e).__name__
    except TimeoutError as e:
        out, kind = {"success": False, "message": str(e)}, "timeout"
    except (Exception, SystemExit) as e:
        kind = f"internal error {type(e).__name__}"
        log.exception("deferred handler of %s%s raised", agent, entry.suffix,
                      extra=log_key(agent + entry.suffix, kind))
        out = {"success": False, "message": f"internal error in {entry.suffix}: {type(e).__name__}: {clip(str(e))}"}
    return _complete(entry, agent, out, kind)


def call_and_wait(sim: Simulation, entry: ApiEntry, agent: str, request: BaseModel | dict[str, Any] | None,
                  max_steps: int = 1_000_000) -> dict[str, Any]:
    """:func:`call`, stepping the simulation until a deferred answer is done (for Python use and tests)."""
    result = call(sim, entry, agent, request)
    for _ in range(max_steps):
        if not isinstance(result, Deferred):
            return result
        sim.step()
        done = finish(sim, entry, agent, result)
        if done is not None:
            return done
    return {"success": False, "message": f"not done after {max_steps} steps"}
