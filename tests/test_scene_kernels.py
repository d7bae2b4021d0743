"""The renderer's compiled passes over the geoms (aibo_sim/scene_kernels.py), on hand-made
frustums and scenes with known answers; the pictures they serve are tested in test_model.py
(culling changes no pixel) and test_lod.py (the levels a camera draws)."""

import math

import mujoco
import numpy as np

from aibo_sim.lod import LEVEL_RADII_PX
from aibo_sim.scene_kernels import outside_view, swap_levels


def square_frustum(near: float, far: float) -> tuple[np.ndarray, np.ndarray]:
    """World normals (columns) and offsets of a 90 x 90 degree frustum looking along +x, up +z
    (so its right is -y), from the origin."""
    s = 1 / math.sqrt(2)
    in_camera = np.array([(s, 0, s), (-s, 0, s), (0, s, s), (0, -s, s), (0, 0, 1), (0, 0, -1)]).T  # right, up, forward
    right, up, forward = (0, -1, 0), (0, 0, 1), (1, 0, 0)
    return np.array([right, up, forward], float).T @ in_camera, np.array([0, 0, 0, 0, -near, far], float)


def test_outside_view_culls_what_lies_outside_and_distant_parts_smaller_than_a_pixel():
    normals, offsets = square_frustum(0.05, 50.0)
    xpos = np.array(
        [
            (2, 0, 0),  # 0: ahead
            (-2, 0, 0),  # 1: behind
            (2, 3, 0),  # 2: left of the view
            (2, 2.05, 0),  # 3: across the left edge (0.035 m outside, radius 0.1)
            (10, 0, 0),  # 4: distant, 2 px wide at 1 m: below a pixel at 10 m
            (1, 0, 0),  # 5: distant, 2 px at 1 m
            (60, 0, 0),  # 6: beyond the far plane
        ],
        float,
    )
    shown = np.array([0, 1, 2, 3, 4, 5, 6], np.intp)
    radius = np.array([0.1, 0.1, 0.1, 0.1, 0.01, 0.01, 0.1])
    distant = np.array([False, False, False, False, True, True, False])
    culled, far, far_depth = np.empty(7, np.intp), np.empty(7, np.intp), np.empty(7)
    counts = outside_view(
        xpos, shown, radius, normals, offsets, np.zeros(3), distant, 100.0, 0.05, culled, far, far_depth
    )
    assert counts == (4, 2)
    assert culled[:4].tolist() == [1, 2, 4, 6]
    assert far[:2].tolist() == [4, 5] and np.allclose(far_depth[:2], [10.0, 1.0], rtol=0, atol=1e-12)


def test_swap_levels_draws_each_small_geom_as_the_level_its_size_calls_for():
    G = mujoco.mjtGeom
    sphere, mesh_type = int(G.mjGEOM_SPHERE), int(G.mjGEOM_MESH)
    geom, site = int(mujoco.mjtObj.mjOBJ_GEOM), int(mujoco.mjtObj.mjOBJ_SITE)
    # Scene entries: geoms 0, 1, 2 and 3, then a site whose objid is 0 (not geom 0).
    types = np.full(5, sphere, np.int32)
    dataids = np.full(5, -1, np.int32)
    objtypes = np.array([geom, geom, geom, geom, site], np.int32)
    objids = np.array([0, 1, 2, 3, 0], np.int32)
    mats = np.tile(np.arange(1, 10, dtype=np.float32), (5, 1))
    row = np.array([0, 1, 2, -1], np.intp)  # geom 3 has no levels
    radius = np.array([0.01, 0.03, 0.1])  # 1, 3 and 10 px at 1 m (100 px a metre)
    meshes = np.array([(10, 11, 12), (13, 14, 15), (16, 17, 18)], np.intp)
    turn = np.tile(np.eye(3, dtype=np.float32), (19, 1, 1))
    turn[15] = ((0, 0, 1), (0, 1, 0), (1, 0, 0))  # MuJoCo swapped this mesh's x and z
    geoms, depths = np.array([0, 1, 2, 3], np.intp), np.ones(4)
    level_radii = np.array(LEVEL_RADII_PX)
    assert level_radii[0] < 1.2 and level_radii[1] < 3 < level_radii[2] < 10  # 1 px: level 0; 3 px: level 2
    swapped = swap_levels(
        types, dataids, objtypes, objids, mats, 5, geoms, depths, 100.0, row, radius, level_radii, meshes, turn
    )
    assert swapped == 2
    assert types.tolist() == [mesh_type, mesh_type, sphere, sphere, sphere]
    assert dataids.tolist() == [2 * 10, 2 * 15, -1, -1, -1]  # MuJoCo's mesh dataid: twice the mesh id
    expected = np.tile(np.arange(1, 10, dtype=np.float32), (5, 1))
    expected[1] = (expected[1].reshape(3, 3) @ turn[15]).ravel()
    assert np.array_equal(mats, expected)


def test_a_kernel_numba_cannot_cache_is_compiled_without_the_cache():
    """``jit.compiled``: where numba has nowhere to keep the compiled code (here a function with no
    source file, as for a read-only install without a writable home), it compiles it anyway."""
    import numba
    import pytest

    from aibo_sim.jit import compiled

    namespace = {}
    exec("def double(x):\n    return 2 * x\n", namespace)
    with pytest.raises(RuntimeError, match="cannot cache"):
        numba.njit(cache=True)(namespace["double"])
    assert compiled(nogil=True)(namespace["double"])(21) == 42
