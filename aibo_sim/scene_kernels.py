"""The renderer's per-frame passes over the geoms, compiled with numba: the culling
(``Renderer``) and the levels of detail (``lod.LevelsOfDetail``).

Both are loops over a few hundred geoms, where numpy's calls cost more than the arithmetic
(~0.4 ms a frame for a match's camera in numpy, most of it the calls' overhead), and both run
without Python's lock (``nogil``): a match's cameras make their frames in parallel threads.
Compiled on first use and cached beside the module; the renderer imports this module, so that
importing ``aibo_sim`` does not load numba.
"""

from __future__ import annotations

import mujoco
import numpy as np

from .jit import compiled

_compiled = compiled(nogil=True, boundscheck=False)
_GEOM, _MESH = int(mujoco.mjtObj.mjOBJ_GEOM), int(mujoco.mjtGeom.mjGEOM_MESH)


@_compiled
def outside_view(xpos, shown, radius, normals, offsets, eye, distant, pixels_per_metre, near, culled, far, far_depth):
    """Sort the geoms ``shown`` (ids; bounding ``radius`` each, m) at world positions ``xpos``
    against the view frustum (inward ``normals`` in world axes, columns, and ``offsets`` of its six
    planes, the fifth the near plane, from the ``eye``): into ``culled`` the ids of those outside
    it, and of the ``distant`` ones (flags by id) smaller than a pixel (2 r ``pixels_per_metre``
    < depth); into ``far`` and ``far_depth`` every distant one's id and depth (m, along the view:
    its distance from the near plane plus ``near``). Returns the counts written to each."""
    culled_count = far_count = 0
    for k in range(shown.size):
        geom = shown[k]
        x, y, z = xpos[geom, 0] - eye[0], xpos[geom, 1] - eye[1], xpos[geom, 2] - eye[2]
        outside = False
        depth = 0.0
        for plane in range(6):
            distance = x * normals[0, plane] + y * normals[1, plane] + z * normals[2, plane] + offsets[plane]
            outside |= distance < -radius[k]
            if plane == 4:
                depth = distance + near
        if distant[geom]:
            outside |= 2 * radius[k] * pixels_per_metre < depth
            far[far_count] = geom
            far_depth[far_count] = depth
            far_count += 1
        if outside:
            culled[culled_count] = geom
            culled_count += 1
    return culled_count, far_count


@_compiled
def swap_levels(
    types,
    dataids,
    objtypes,
    objids,
    mats,
    count,
    geoms,
    depths,
    pixels_per_metre,
    row,
    radius,
    level_radii,
    meshes,
    turn,
):
    """Draw the scene's first ``count`` geoms (their ``types``, ``dataids``, ``objtypes``,
    ``objids`` and ``mats``, the scene's fields) that are among ``geoms`` (ids, at ``depths``) as
    the level their size in the picture calls for: the first of ``level_radii`` (pixels) at or
    above the outline's radius there (``radius`` m by ``row``, -1: no levels), none past the last;
    ``meshes`` (row, level) the level's mesh ids, ``turn`` (mesh, 3, 3) the turn that puts back
    MuJoCo's turn of each mesh (identity where none). Returns the number of geoms swapped."""
    levels = level_radii.size
    level = np.full(row.size, levels, np.int64)  # per geom id: MuJoCo's own shape
    for k in range(geoms.size):
        r = row[geoms[k]]
        if r >= 0:
            radius_px = radius[r] * pixels_per_metre / max(depths[k], 1e-9)
            chosen = 0
            while chosen < levels and level_radii[chosen] < radius_px:
                chosen += 1
            level[geoms[k]] = chosen
    swapped = 0
    rotated = np.empty(9, np.float32)
    for i in range(count):
        if objtypes[i] != _GEOM:  # objid is a geom id in these alone
            continue
        geom = objids[i]
        if level[geom] == levels:
            continue
        mesh = meshes[row[geom], level[geom]]
        for a in range(3):
            for b in range(3):
                rotated[3 * a + b] = (
                    mats[i, 3 * a] * turn[mesh, 0, b]
                    + mats[i, 3 * a + 1] * turn[mesh, 1, b]
                    + mats[i, 3 * a + 2] * turn[mesh, 2, b]
                )
        mats[i, :] = rotated
        types[i] = _MESH
        dataids[i] = 2 * mesh
        swapped += 1
    return swapped
