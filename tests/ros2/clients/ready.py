"""Wait for the simulation's latched /sigcore/ready."""

from common import Client, emit

c = Client("ready_probe")
emit({"ready": c.wait_ready(60.0)})
