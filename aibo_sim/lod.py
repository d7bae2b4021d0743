"""Levels of detail for the robots a head camera sees in a match.

MuJoCo draws every sphere, capsule, cylinder and ellipsoid with the same facets whatever its
size in the picture (16 x 10 in ``Renderer``'s fast quality, ~300 triangles), and on Mesa's
llvmpipe the triangles are the cost: a robot 3 m away, 20 pixels long, costs as many as one
filling the picture. A match's model holds, beside those shapes, coarser copies of every robot's
visual geoms as meshes (``add_levels_of_detail``): ``LEVEL_SLICES`` facets around, each level used
while its polygon stays within ``MAX_ERROR_PX`` of the true outline in the picture (a polygon of
n sides departs from its circle of radius r by r (1 - cos(pi / n))); larger geoms keep MuJoCo's
own shapes. ``LevelsOfDetail`` swaps them into a renderer's scene per frame. The meshes are
assets only: no geom uses them, so the physics and a single robot's model are unchanged.
"""

from __future__ import annotations

import math

import mujoco
import numpy as np

LEVEL_SLICES = (6, 8, 12)  # facets around a level's circles; stacks: half as many pole to pole
MAX_ERROR_PX = 0.15  # the outline's largest departure (pixels) a level may make
LEVEL_RADII_PX = tuple(MAX_ERROR_PX / (1 - math.cos(math.pi / n)) for n in LEVEL_SLICES)  # 1.1, 2.0, 4.4
G = mujoco.mjtGeom
SHAPES = tuple(int(t) for t in (G.mjGEOM_SPHERE, G.mjGEOM_ELLIPSOID, G.mjGEOM_CAPSULE, G.mjGEOM_CYLINDER, G.mjGEOM_BOX))


def mesh_name(geom_type: int, size, slices: int) -> str:
    """The name of the LOD mesh of a geom shape (type and size) at ``slices`` (a box has one)."""
    kind = mujoco.mjtGeom(geom_type).name.removeprefix("mjGEOM_").lower()
    used = {"sphere": 1, "capsule": 2, "cylinder": 2}.get(kind, 3)  # the half sizes the shape reads
    dims = "_".join(f"{s:.6g}" for s in np.asarray(size, float)[:used])
    return f"lod_{kind}_{dims}" + ("" if kind == "box" else f"_{slices}")


def outline_radius(geom_type: int, size) -> float:
    """The radius (m) of the curve whose facets a level replaces: a sphere's, a capsule's or a
    cylinder's circle, an ellipsoid's largest half-axis, a box's half diagonal."""
    size = np.asarray(size, float)
    if geom_type == G.mjGEOM_ELLIPSOID:
        return float(size.max())
    if geom_type == G.mjGEOM_BOX:
        return float(np.linalg.norm(size))
    return float(size[0])


def _revolve(rings, slices: int):
    """A closed surface of revolution about z: ``rings`` top to bottom as (rho, z, normal_rho,
    normal_z); a ring of rho 0 is a pole (one vertex); consecutive rings at one place (an edge
    with two normals) are not joined. Vertices (n, 3), normals (n, 3), faces (m, 3) outward."""
    angles = 2 * np.pi * np.arange(slices) / slices
    cos, sin = np.cos(angles), np.sin(angles)
    vertices, normals, faces, previous = [], [], [], None
    for rho, z, n_rho, n_z in rings:
        start = len(vertices)
        if rho == 0:
            vertices.append((0.0, 0.0, z))
            normals.append((0.0, 0.0, n_z))
            ring = [start] * slices
        else:
            vertices += [(rho * c, rho * s, z) for c, s in zip(cos, sin)]
            normals += [(n_rho * c, n_rho * s, n_z) for c, s in zip(cos, sin)]
            ring = list(range(start, start + slices))
        if previous is not None and previous[1] != (rho, z):
            upper = previous[0]
            for j in range(slices):
                k = (j + 1) % slices
                if upper[j] != upper[k]:
                    faces.append((upper[j], ring[j], upper[k]))
                if ring[j] != ring[k]:
                    faces.append((upper[k], ring[j], ring[k]))
        previous = ring, (rho, z)
    return np.array(vertices), np.array(normals), np.array(faces)


def _arc(radius: float, z0: float, first: float, last: float, stacks: int):
    """Rings of a sphere's arc from polar angle ``first`` to ``last`` (radians), centred at z0."""
    sines_cosines = [(round(math.sin(t), 12), round(math.cos(t), 12)) for t in np.linspace(first, last, stacks + 1)]
    return [(radius * s, z0 + radius * c, s, c) for s, c in sines_cosines]  # rounded: the poles' rho exactly 0


def lod_shape(geom_type: int, size, slices: int):
    """Vertices, normals and faces of a geom's shape (MuJoCo's conventions: half sizes, z the
    axis of capsules and cylinders) with ``slices`` facets around."""
    size = np.asarray(size, float)
    stacks = max(2, slices // 2)
    if geom_type in (G.mjGEOM_SPHERE, G.mjGEOM_ELLIPSOID):
        vertices, normals, faces = _revolve(_arc(1.0, 0.0, 0.0, math.pi, stacks), slices)
        scale = np.full(3, size[0]) if geom_type == G.mjGEOM_SPHERE else size
        normals = normals / scale  # the normal of a scaled sphere: scaled by the inverse
        return vertices * scale, normals / np.linalg.norm(normals, axis=1, keepdims=True), faces
    if geom_type == G.mjGEOM_CAPSULE:
        radius, half = size[0], size[1]
        cap = max(1, stacks // 2)
        rings = _arc(radius, half, 0.0, math.pi / 2, cap) + _arc(radius, -half, math.pi / 2, math.pi, cap)
        return _revolve(rings, slices)
    if geom_type == G.mjGEOM_CYLINDER:
        radius, half = size[0], size[1]
        rings = [(0, half, 0, 1), (radius, half, 0, 1), (radius, half, 1, 0), (radius, -half, 1, 0)]
        return _revolve(rings + [(radius, -half, 0, -1), (0, -half, 0, -1)], slices)
    if geom_type == G.mjGEOM_BOX:
        vertices, normals, faces = [], [], []
        for axis in range(3):
            u, w = np.eye(3)[(axis + 1) % 3], np.eye(3)[(axis + 2) % 3]
            for sign in (-1, 1):
                normal, start = sign * np.eye(3)[axis], len(vertices)
                vertices += [(normal + a * u + b * w) * size for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))]
                normals += [normal] * 4
                quad = [start, start + 1, start + 2, start + 3][::sign]
                faces += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
        return np.array(vertices), np.array(normals), np.array(faces)
    raise ValueError(f"no level of detail for geom type {geom_type}")


def add_levels_of_detail(spec: mujoco.MjSpec, bodies, groups) -> None:
    """Add to ``spec`` the LOD meshes (one per shape and level) of the geoms in ``groups`` of the
    robots whose root bodies are named ``bodies``, at the sizes MuJoCo compiles them to (a
    ``fromto`` gives a capsule's length)."""
    model = spec.compile()
    for body in bodies:
        in_robot = model.body_rootid[model.geom_bodyid] == model.body(body).id
        shaped = np.isin(model.geom_type, SHAPES)
        for g in np.flatnonzero(in_robot & shaped & np.isin(model.geom_group, groups)):
            kind, size = int(model.geom_type[g]), model.geom_size[g]
            for slices in LEVEL_SLICES:
                if spec.mesh(name := mesh_name(kind, size, slices)) is None:
                    vertices, normals, faces = lod_shape(kind, size, slices)
                    mesh = spec.add_mesh(name=name)
                    mesh.uservert, mesh.usernormal = vertices.ravel().tolist(), normals.ravel().tolist()
                    mesh.userface = faces.ravel().tolist()


class LevelsOfDetail:
    """Swaps the model's LOD meshes into a scene for ``geoms`` (ids) that are small in the picture.

    ``apply`` takes the scene's geom fields (``scene_geom_fields``) after ``mjv_updateScene``;
    the geoms keep their ids, colours and materials (segmentation and labels are unchanged)."""

    def __init__(self, model: mujoco.MjModel, geoms):
        geoms = np.asarray(geoms, np.intp)

        def mesh_ids(geom: int) -> list[int]:
            kind, size = int(model.geom_type[geom]), model.geom_size[geom]
            if kind not in SHAPES:
                return [-1] * len(LEVEL_SLICES)
            return [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MESH, mesh_name(kind, size, n)) for n in LEVEL_SLICES]

        meshes = np.array([mesh_ids(g) for g in geoms], np.intp).reshape(-1, len(LEVEL_SLICES))
        covered = (meshes >= 0).all(axis=1)
        self.geoms = geoms[covered]
        self._meshes = meshes[covered]
        self._row = np.full(model.ngeom, -1, np.intp)  # by geom id: its row of meshes, -1 without
        self._row[self.geoms] = np.arange(self.geoms.size)
        self._radius = np.array([outline_radius(int(model.geom_type[g]), model.geom_size[g]) for g in self.geoms])
        # MuJoCo turns a mesh's vertices to its principal axes (mesh_quat; the shapes are symmetric,
        # so it moves none): drawn at the geom's pose, a mesh needs that turn put back (axis swaps).
        rotations = np.zeros((model.nmesh, 9))
        for m in range(model.nmesh):
            mujoco.mju_quat2Mat(rotations[m], model.mesh_quat[m])
        self._mesh_rot = rotations.reshape(-1, 3, 3).astype(np.float32)
        self._level_radii = np.array(LEVEL_RADII_PX)
        from . import scene_kernels  # numba, loaded by the first renderer rather than by every import of aibo_sim

        self._swap = scene_kernels.swap_levels

    def apply(self, fields: dict, count: int, geoms, depth, pixels_per_metre: float) -> int:
        """Draw the covered geoms among the scene's first ``count`` as the level their size in
        the picture calls for: ``geoms`` (ids) at ``depth`` (m, along the view), where a metre
        spans ``pixels_per_metre`` at 1 m. Returns the number drawn coarser."""
        return self._swap(
            fields["type"],
            fields["dataid"],
            fields["objtype"],
            fields["objid"],
            fields["mat"],
            count,
            geoms,
            depth,
            pixels_per_metre,
            self._row,
            self._radius,
            self._level_radii,
            self._meshes,
            self._mesh_rot,
        )
