"""The agent API table: every topic and service of every agent, typed, with its handler."""

from .call import call, call_and_wait, finish
from .deferred import Deferred
from .table import ALL, BODY, ROBOT, ApiEntry, api_table, entries_for

__all__ = ["ALL", "BODY", "ROBOT", "ApiEntry", "Deferred", "api_table", "call", "call_and_wait", "entries_for",
           "finish"]
