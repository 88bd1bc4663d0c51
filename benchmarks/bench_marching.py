"""The classroom scene at 640x480 with each faster-marching setting, on every backend, in one run.

Prints the median time per frame and mean steps per pixel of each (setting, backend,
precision), then the ratios issue 4 asks about (opencl against numpy at the same precision,
opencl against gpu). Results and the command are in docs/performance.md.
"""
import time, numpy as np, dataclasses as dc, marchlab
sc = marchlab.load_scene("classroom")
configs = {"plain": {}, "auto": dict(relaxation="auto"), "auto+spheres": dict(relaxation="auto", bounding_spheres=True), "plain+spheres": dict(bounding_spheres=True)}
res = {}
for name, c in configs.items():
    s2 = dc.replace(sc, render=dc.replace(sc.render, **c))
    for backend, prec in [("gpu","float32"),("opencl","float32"),("opencl","float64"),("numpy","float32"),("numpy","float64")]:
        rep = 3 if backend == "numpy" else 7
        f = marchlab.render(s2, 640, 480, backend=backend, precision=prec)
        ts = []
        for _ in range(rep):
            t0 = time.perf_counter(); f = marchlab.render(s2, 640, 480, backend=backend, precision=prec); ts.append(time.perf_counter() - t0)
        res[(name, backend, prec)] = 1000*np.median(ts)
        print(f"{name:14s} {backend:6s} {prec}  median {1000*np.median(ts):7.1f} ms  best {1000*min(ts):7.1f}  steps {f.steps.mean():.1f}", flush=True)
for name in configs:
    g = res[(name,"gpu","float32")]
    for prec in ["float32","float64"]:
        o, n = res[(name,"opencl",prec)], res[(name,"numpy",prec)]
        print(f"{name:14s} {prec}: opencl vs numpy {n/o:.1f}x, opencl/gpu {o/g:.1f}x")
