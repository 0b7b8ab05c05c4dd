"""The Python package in a few lines: a parameter file changed from Python, points evaluated as
NumPy arrays, a render, a bake and a mesh with progress (pip install "dqjulia[numpy]").

Usage: python3 examples/python_api.py [OUT_FOLDER]     (default: out/)
"""

import os
import sys

import numpy as np

import dqjulia

out = sys.argv[1] if len(sys.argv) > 1 else "out"
os.makedirs(out, exist_ok=True)
here = os.path.dirname(os.path.abspath(__file__))


def progress(fraction):
    print("\r%3.0f %%" % (100 * fraction), end="" if fraction < 1 else "\n", flush=True)


with dqjulia.Fractal.from_file(os.path.join(here, "paper-test2-2.json")) as fractal:
    fractal.update({"render": {"width": 480, "height": 360}})

    # Which points of a plane through the slice are inside (did not escape)?
    xs = np.linspace(-1.5, 1.5, 201)
    plane = np.stack(np.meshgrid(xs, xs, [0.0], indexing="ij"), axis=-1)[:, :, 0]  # (201, 201, 3)
    samples = fractal.evaluate_slice(plane)
    print("inside: %.1f %% of the plane z = 0" % (100 * np.mean(samples["n"] == 0)))

    fractal.render_to_file(os.path.join(out, "python_api.png"), progress=progress)
    stats = fractal.bake(os.path.join(out, "python_api.vdb"), resolution=128, progress=progress)
    print("baked %d active voxels in %.2f s" % (stats.active_voxels, stats.seconds))
    mesh = fractal.mesh(resolution=128, triangulate=True)
    print("mesh: %d vertices, %d triangles" % (len(mesh.vertices), len(mesh.triangles)))
