"""Hostile input: generated world files that must each be refused with a located message."""
