"""The NumPy reference sphere tracer: the ground truth every other backend is checked against.

Read it in this order: sdf.py (distance formulas), scene_sdf.py (a scene's SDF), march.py
(sphere tracing), normals.py, lights.py, shading.py, shadows.py, render.py (the pipeline);
texture.py and environment.py sample environment maps.
"""
