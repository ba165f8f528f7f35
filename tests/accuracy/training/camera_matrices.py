"""OpenEXR camera attributes from a Blender camera, in plain Python (no numpy, no mathutils).

Blender gives camera-to-world in OpenGL's convention (x right, y up, -z forward) and an OpenGL
projection (clip = P * camera, w = -z). OpenEXR's standard attributes are row-vector Imath
matrices (p' = p * M, translation in the last row), flattened row by row:
  worldToCamera: world to camera space with x right, y up, +z forward;
  worldToNDC:    world to NDC, (0,0) the top-left and (1,1) the bottom-right corner of the
                 display window after the divide by w (w = camera-space z); z is OpenGL's clip z.
Used by scenes.py (inside Blender) and check_cameras.py (plain python3), so the matrices that
go into the headers are the ones that are checked against the sample data.
"""


def matmul(a, b):
    return [[sum(a[i][k] * b[k][j] for k in range(4)) for j in range(4)] for i in range(4)]


def transpose(a):
    return [[a[j][i] for j in range(4)] for i in range(4)]


def rigid_inverse(m):
    """Inverse of a rotation + translation (column-vector 4x4, no scale or shear)."""
    r_t = [[m[j][i] for j in range(3)] for i in range(3)]
    t = [m[i][3] for i in range(3)]
    out = [[r_t[i][0], r_t[i][1], r_t[i][2], -sum(r_t[i][k] * t[k] for k in range(3))]
           for i in range(3)]
    return out + [[0.0, 0.0, 0.0, 1.0]]


# OpenGL camera (-z forward) to OpenEXR camera (+z forward).
FLIP_Z = [[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, -1.0, 0], [0, 0, 0, 1.0]]
# OpenGL clip space (x right, y up, [-1, 1] after the divide) to NDC (top-left origin, [0, 1]);
# z and w are kept: x' = (x + w) / 2, y' = (w - y) / 2.
CLIP_TO_NDC = [[0.5, 0, 0, 0.5], [0, -0.5, 0, 0.5], [0, 0, 1.0, 0], [0, 0, 0, 1.0]]


def flat_row_vector(column_vector_matrix):
    """A column-vector matrix as Imath's row-vector layout, flattened row-major."""
    return [v for row in transpose(column_vector_matrix) for v in row]


def world_to_camera(camera_to_world_gl):
    return flat_row_vector(matmul(FLIP_Z, rigid_inverse(camera_to_world_gl)))


def world_to_ndc(camera_to_world_gl, projection_gl):
    return flat_row_vector(
        matmul(CLIP_TO_NDC, matmul(projection_gl, rigid_inverse(camera_to_world_gl))))


def transform_point(flat_m, p):
    """p (x, y, z) through a flattened row-vector matrix: returns (x', y', z', w')."""
    v = (p[0], p[1], p[2], 1.0)
    return tuple(sum(v[k] * flat_m[4 * k + j] for k in range(4)) for j in range(4))
