"""The packet march of benchmarks/bench_opencl_packets.py computes what the scalar one does.

The benchmark's speed-ups (docs/performance.md, "packets of rays") mean something only if the
three kernels march the same rays to the same result: the same operations in the same order,
lane by lane, so t and the step count of every pixel must agree to the bit, at both
precisions and for each packet width.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

BENCHMARK = Path(__file__).resolve().parents[2] / "benchmarks" / "bench_opencl_packets.py"


def load_benchmark():
    spec = importlib.util.spec_from_file_location("bench_opencl_packets", BENCHMARK)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("precision", ["float32", "float64"])
@pytest.mark.parametrize("lanes", [4, 16])
def test_packet_and_interleaved_marches_equal_the_one_ray_march_to_the_bit(
        opencl_device, precision, lanes):
    if precision == "float64" and not opencl_device.fp64:
        pytest.skip(f"{opencl_device.label} has no float64")
    results = load_benchmark().march_three_ways(64, 48, precision, lanes, repeat=1)
    _, t, steps = results["one_ray"]
    assert (t > 0).mean() > 0.5 and (t == -1).any()     # floor and spheres hit, sky missed
    assert steps.max() > 20                              # grazing rays: a real march
    for name in ("interleaved", "packets"):
        _, t_other, steps_other = results[name]
        np.testing.assert_array_equal(t_other, t, err_msg=name)
        np.testing.assert_array_equal(steps_other, steps, err_msg=name)
