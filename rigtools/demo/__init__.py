"""Synthetic rig runs, writers for the reference formats, and the demo job."""

__all__: list[str] = []
