"""Call ``<service>`` (sigcore_msgs GetObjPosition, the agent itself) once and wait up to 30 s for the answer, which
the test holds back until it deletes the agent.

Argument: the service name.
"""

import sys

from common import Client, emit, todict
from sigcore_msgs import srv

c = Client("call_deleted")
got = c.call(srv.GetObjPosition, sys.argv[1], timeout=30.0, name="")
emit({"answer": None if got is None else todict(got)})
