"""Self-checks for the physics exercises (impulses, friction, integrators)."""

__all__: list[str] = []
