"""The model, marchlab's ground floor: the scene as plain data and everything that describes it.

Scenes, shapes, materials, lights, bodies and their validated fields; scene files and the
builder; the camera model and its anti-aliasing samples, the `Frame` a renderer returns, and
small vector helpers. It imports no engine: the tracers, the physics and the front door read
it; it reads none of them.
"""
