"""The agent API table: every topic and service of every agent, typed, with its handler."""

from .call import call
from .table import ALL, BODY, ROBOT, ApiEntry, api_table, entries_for

__all__ = ["ALL", "BODY", "ROBOT", "ApiEntry", "api_table", "call", "entries_for"]
