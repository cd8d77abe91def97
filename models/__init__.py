"""models: spur-gear physics as pure functions of geometry, material and operating point.

Never imports rigtools. Filled by the geometry, stiffness, thermal and dynamics issues.
"""

__all__: list[str] = []
