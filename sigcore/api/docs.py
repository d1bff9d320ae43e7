"""Generate ``docs/api.md`` from the API table."""

from __future__ import annotations

from .table import ApiEntry, api_table

_TITLES = {"publish": "Topics each agent publishes", "subscribe": "Topics each agent subscribes to",
           "service": "Services of each agent"}


def _fields(model: object) -> str:
    fields = getattr(model, "model_fields", None)
    if fields is None:
        return "–"
    return ", ".join(f"`{n}`" for n in fields) or "–"


def api_markdown(table: list[ApiEntry] | None = None) -> str:
    """The API reference as Markdown (one table per direction)."""
    table = table if table is not None else api_table()
    lines = [
        "# The agent API",
        "",
        "Generated from `sigcore/api/table.py` by `sigcore api --markdown` (a test checks it is current).",
        "",
        "Every endpoint is `<agent><suffix>`, e.g. `robot_000_get_obj_position`. Units are SI (metres, radians, "
        "seconds, kilograms), frames z up. A `name` field targets another entity; empty means the agent itself. "
        "Type names are those of the ROS 2 package `sigcore_msgs` (generated from the same table by "
        "`sigcore interfaces`). Every service response carries `success` and `message`: a refused request "
        "answers `success=false` and says what was wrong and what would be valid; nothing stops the simulation.",
        "",
        "Over ROS 2, the agents that have `<agent><suffix>` endpoints are the `sigros_agents` setting's (default "
        "`auto`: every robot, human and bodiless agent, and the objects with a controller); each subscribed or "
        "service function whose request has `name` (the entity) is also one shared endpoint "
        "`/sigcore/sigros/<suffix without its underscore>` that serves any agent by that `name` "
        "(see [ros2.md](ros2.md), \"Many entities\").",
        "",
        "Kinds: `robot`, `object`, `human`, `agent` (a bare agent with no body, which must name its target).",
        "",
    ]
    for direction in ("publish", "subscribe", "service"):
        lines += [f"## {_TITLES[direction]}", ""]
        if direction == "service":
            lines += ["| suffix | type | request | response | kinds | meaning |", "|---|---|---|---|---|---|"]
        else:
            lines += ["| suffix | type | fields | kinds | meaning |", "|---|---|---|---|---|"]
        for e in table:
            if e.direction != direction:
                continue
            kinds = ", ".join(sorted(e.kinds)) if len(e.kinds) < 4 else "all"
            origin = "" if e.origin == "sig_ros" else f" ({e.origin} addition)"
            if direction == "service":
                resp = ", ".join(f"`{n}`" for n in (e.response.model_fields if e.response else {})
                                 if n not in ("success", "message"))
                lines.append(f"| `{e.suffix}` | `{e.ros_type}` | {_fields(e.request)} | {resp or '–'} | {kinds} | "
                             f"{e.doc}{origin} |")
            else:
                lines.append(f"| `{e.suffix}` | `{e.ros_type}` | {_fields(e.request)} | {kinds} | {e.doc}{origin} |")
        lines.append("")
    return "\n".join(lines)
