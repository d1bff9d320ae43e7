"""Calls a service whose callback raises (twice), then the action node's and the main node's other services."""

from common import Client, emit
from rcl_interfaces.srv import GetParameterTypes, ListParameters

c = Client("raising_probe")
c.wait_ready()
out = {"raising": [c.call(GetParameterTypes, "/sigcore_actions/get_parameter_types", timeout=3.0,
                          names=["use_sim_time"]) is not None for _ in range(2)]}
for node in ("/sigcore_actions", "/sigcore"):
    res = c.call(ListParameters, f"{node}/list_parameters")
    out[node] = None if res is None else list(res.result.names)
emit(out)
