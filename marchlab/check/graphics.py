"""Self-checks for the graphics exercises (SDFs, lighting, shadows, reflections)."""

__all__: list[str] = []
