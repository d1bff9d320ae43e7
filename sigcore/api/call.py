"""Calling an API entry: validate the request, run the handler, turn refusals into error responses."""

from __future__ import annotations

import logging
from typing import TYPE_CHECKING, Any

from pydantic import BaseModel, ValidationError

from ..agent.exceptions import ApiError
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


def call(sim: Simulation, entry: ApiEntry, agent: str, request: BaseModel | dict[str, Any] | None) -> dict[str, Any]:
    """Run ``entry`` for ``agent``. Never raises for bad input.

    Returns:
        For services, every response field including ``success`` and ``message`` (what was wrong, if anything).
        For subscribed topics, ``{"success": ..., "message": ...}``.
    """
    if entry.handler is None or entry.request is None:
        return {"success": False, "message": f"{entry.suffix} is published by the simulation, not handled"}
    try:
        if isinstance(request, BaseModel) and not isinstance(request, entry.request):
            request = request.model_dump()
        req = request if isinstance(request, entry.request) else entry.request.model_validate(request or {})
        fields = entry.handler(sim, agent, req) or {}
        out: dict[str, Any] = {**fields, "success": True, "message": ""}
    except ValidationError as e:
        out = {"success": False, "message": _validation_message(entry, e)}
    except ApiError as e:
        out = {"success": False, "message": str(e)}
    except Exception as e:  # a bug must not stop the simulation either; report it loudly
        log.exception("handler of %s%s raised", agent, entry.suffix)
        out = {"success": False, "message": f"internal error in {entry.suffix}: {type(e).__name__}: {e}"}
    if not out["success"]:
        log.warning("%s%s refused: %s", agent, entry.suffix, out["message"])
    if entry.response is not None:
        defaults = entry.response().model_dump()
        return {**defaults, **out}
    return out
