"""Calling an API entry: validate the request, run the handler, turn refusals into error responses."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel, ValidationError

from ..agent.exceptions import ApiError
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
        fields = entry.handler(sim, agent, req) or {}
        if isinstance(fields, Deferred):
            return fields
        out: dict[str, Any] = {**fields, "success": True, "message": ""}
    except ValidationError as e:
        out = {"success": False, "message": _validation_message(entry, e)}
    except ApiError as e:
        out = _refused(entry, e)
    except Exception as e:  # a bug must not stop the simulation either; report it loudly
        log.exception("handler of %s%s raised", agent, entry.suffix)
        out = {"success": False, "message": f"internal error in {entry.suffix}: {type(e).__name__}: {e}"}
    return _complete(entry, agent, out)


def _refused(entry: ApiEntry, e: ApiError) -> dict[str, Any]:
    """The error response of a refusal: the error's fields that the response type has, ``success`` false."""
    known = entry.response.model_fields if entry.response is not None else {}
    return {**{k: v for k, v in e.fields.items() if k in known}, "success": False, "message": str(e)}


def _complete(entry: ApiEntry, agent: str, out: dict[str, Any]) -> dict[str, Any]:
    if not out["success"]:
        log.warning("%s%s refused: %s", agent, entry.suffix, out["message"])
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
    except ApiError as e:
        out = _refused(entry, e)
    except TimeoutError as e:
        out = {"success": False, "message": str(e)}
    except Exception as e:
        log.exception("deferred handler of %s%s raised", agent, entry.suffix)
        out = {"success": False, "message": f"internal error in {entry.suffix}: {type(e).__name__}: {e}"}
    return _complete(entry, agent, out)


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
