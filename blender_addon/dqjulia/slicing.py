"""The slice as the preview shader needs it: the 8-D origin and axes after the rotations,
and the slice's largest stretch. Pure Python (no bpy), read from a parameter document.

This mirrors core/src/kernel/slice.cpp (rotated(), stretchOf()); the Blender tests hold the two
equal by mapping points both ways (dqj_evaluate_slice_points against dqj_evaluate_points
at the points mapped here). Bounds and emptiness are not recomputed here: they come from
the core (dqj_inspect_json).
"""

import math

AXIS_NAMES = ("a.s", "a.i", "a.j", "a.k", "b.s", "b.i", "b.j", "b.k")


def axis_index(name):
    return AXIS_NAMES.index(name.strip())


def base_axes(slice_doc):
    """The three 8-vectors of the document's slice.axes (names or vectors)."""
    axes = slice_doc.get("axes", "a.s,a.i,a.j")
    if isinstance(axes, str):
        result = []
        for name in axes.split(","):
            vector = [0.0] * 8
            vector[axis_index(name)] = 1.0
            result.append(vector)
        return result
    return [[float(x) for x in axis] for axis in axes]


def effective_slice(document):
    """(origin, [x_axis, y_axis, z_axis]) in 8-D, the rotations applied in order."""
    slice_doc = document.get("slice", {})
    origin = [float(x) for x in slice_doc.get("origin", [0.0] * 8)]
    axes = base_axes(slice_doc)
    for rotation in slice_doc.get("rotations", []):
        first_name, second_name = rotation["plane"].split(",")
        first, second = axis_index(first_name), axis_index(second_name)
        radians = math.radians(float(rotation.get("degrees", 0.0)))
        c, s = math.cos(radians), math.sin(radians)
        for axis in axes:
            u, v = axis[first], axis[second]
            axis[first] = c * u - s * v
            axis[second] = s * u + c * v
    return origin, axes


def map_point(origin, axes, p):
    """The 8-D point of slice point p = (x, y, z)."""
    return [origin[i] + p[0] * axes[0][i] + p[1] * axes[1][i] + p[2] * axes[2][i] for i in range(8)]


def _symmetric_eigenvalues(m):
    """Eigenvalues of a symmetric 3x3 matrix (closed form, trigonometric)."""
    p1 = m[0][1] ** 2 + m[0][2] ** 2 + m[1][2] ** 2
    trace = m[0][0] + m[1][1] + m[2][2]
    if p1 == 0.0:
        return sorted([m[0][0], m[1][1], m[2][2]])
    q = trace / 3.0
    p2 = (m[0][0] - q) ** 2 + (m[1][1] - q) ** 2 + (m[2][2] - q) ** 2 + 2.0 * p1
    p = math.sqrt(p2 / 6.0)
    b = [[(m[i][j] - (q if i == j else 0.0)) / p for j in range(3)] for i in range(3)]
    det_b = (
        b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1])
        - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0])
        + b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0])
    )
    r = max(-1.0, min(1.0, det_b / 2.0))
    phi = math.acos(r) / 3.0
    largest = q + 2.0 * p * math.cos(phi)
    smallest = q + 2.0 * p * math.cos(phi + 2.0 * math.pi / 3.0)
    middle = trace - largest - smallest
    return sorted([smallest, middle, largest])


def stretch(axes):
    """(largest, smallest) singular value of the 8x3 axis matrix: how much 3-D lengths stretch."""
    gram = [[sum(axes[i][k] * axes[j][k] for k in range(8)) for j in range(3)] for i in range(3)]
    values = _symmetric_eigenvalues(gram)
    return math.sqrt(max(0.0, values[2])), math.sqrt(max(0.0, values[0]))
