"""Levels of detail for the other robots a head camera sees (aibo_sim/lod.py): the coarse shapes lie
on the true surfaces and close; a match's model holds one for every visual geom a camera draws, a
lone robot's model none; the renderer draws far robots with them, keeping outlines, colours and
labels, and leaves out their parts smaller than a pixel."""

import math

import mujoco
import numpy as np
import pytest

from aibo_sim.camera.head import BEHIND_CAMERA_GROUP, HEAD_CAMERA_GROUPS
from aibo_sim.lod import LEVEL_RADII_PX, LEVEL_SLICES, MAX_ERROR_PX, LevelsOfDetail, lod_shape
from aibo_sim.render import Renderer, scene_geom_fields
from aibo_sim.sim import Simulation
from aibo_sim.team import RobotSpec

G = mujoco.mjtGeom
SHAPES = [
    (G.mjGEOM_SPHERE, (0.03, 0, 0)),
    (G.mjGEOM_ELLIPSOID, (0.112, 0.05, 0.03)),
    (G.mjGEOM_CAPSULE, (0.017, 0.035, 0)),
    (G.mjGEOM_CYLINDER, (0.012, 0.04, 0)),
    (G.mjGEOM_BOX, (0.05, 0.002, 0.028)),
]


def surface_distance(kind, size, points):
    """How far (m) points lie from the true surface of a geom shape (signed: outside positive)."""
    r, h = size[0], size[1]
    if kind == G.mjGEOM_SPHERE:
        return np.linalg.norm(points, axis=1) - r
    if kind == G.mjGEOM_ELLIPSOID:  # exact on the surface only: 0 there
        return np.sqrt(((points / size) ** 2).sum(axis=1)) - 1
    if kind == G.mjGEOM_CAPSULE:
        axis = np.clip(points[:, 2], -h, h)
        return np.linalg.norm(points - np.c_[0 * axis, 0 * axis, axis], axis=1) - r
    if kind == G.mjGEOM_CYLINDER:
        return np.maximum(np.hypot(points[:, 0], points[:, 1]) - r, np.abs(points[:, 2]) - h)
    return (np.abs(points) - size).max(axis=1)


@pytest.mark.parametrize("slices", LEVEL_SLICES)
@pytest.mark.parametrize("kind, size", SHAPES, ids=lambda v: getattr(v, "name", ""))
def test_coarse_shapes_lie_on_the_true_surface_closed_and_facing_out(kind, size, slices):
    vertices, normals, faces = lod_shape(kind, size, slices)
    assert np.abs(surface_distance(kind, np.asarray(size), vertices)).max() < 1e-9
    assert np.allclose(np.linalg.norm(normals, axis=1), 1)
    corners = vertices[faces]
    face_normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    assert (np.linalg.norm(face_normals, axis=1) > 1e-6 * np.square(size).max()).all()  # no degenerate triangle
    # Outward: each face turns the way its vertices' normals point.
    assert ((face_normals[:, None, :] * normals[faces]).sum(axis=2) > 0).all()
    # Closed: on the vertices' places, every edge belongs to exactly two faces, once each way.
    _, place = np.unique(vertices.round(12), axis=0, return_inverse=True)
    edges = [(place[a], place[b]) for f in faces for a, b in ((f[0], f[1]), (f[1], f[2]), (f[2], f[0]))]
    assert len(set(edges)) == len(edges) and all((b, a) in set(edges) for a, b in edges)
    # The polygon's outline departs from the circle by r (1 - cos(pi / n)): the level's radius in
    # pixels keeps that within MAX_ERROR_PX.
    level = LEVEL_SLICES.index(slices)
    assert math.isclose(LEVEL_RADII_PX[level] * (1 - math.cos(math.pi / slices)), MAX_ERROR_PX)


TWO = (RobotSpec("red", 1, (0.0, 0.0, 0.0)), RobotSpec("blue", 1, (1.0, 0.0, 180.0)))


@pytest.fixture(scope="module")
def two():
    sim = Simulation(robots=TWO)
    yield sim
    sim.world.close()


def camera_geoms(model, robot_root: int) -> np.ndarray:
    shown = np.isin(model.geom_group, (*HEAD_CAMERA_GROUPS, BEHIND_CAMERA_GROUP))
    return np.flatnonzero(shown & (model.body_rootid[model.geom_bodyid] == robot_root))


def test_a_match_model_has_coarse_copies_of_every_geom_a_camera_draws_a_lone_robot_none(two):
    model = two.model
    for robot in two.world.robots:
        drawn = camera_geoms(model, model.body_rootid[robot._body])
        lod = LevelsOfDetail(model, drawn)
        assert drawn.size > 40 and np.array_equal(lod.geoms, drawn)  # every one: no mesh in the robot
    lod_meshes = [m for m in range(model.nmesh) if model.mesh(m).name.startswith("lod_")]
    assert np.abs(model.mesh_pos[lod_meshes]).max() < 1e-9  # symmetric: MuJoCo turns them, moves none
    lone = Simulation()
    assert not any(lone.model.mesh(m).name.startswith("lod_") for m in range(lone.model.nmesh))
    assert LevelsOfDetail(lone.model, camera_geoms(lone.model, lone.model.body_rootid[lone._body])).geoms.size == 0
    # Assets only: the two robots' bodies weigh and hold what a lone robot's does.
    masses = model.body_subtreemass[[robot._body for robot in two.world.robots]]
    assert np.allclose(masses, lone.model.body_subtreemass[lone._body])
    lone.close()


def test_scene_geom_fields_are_the_scene_geoms_the_bindings_show(two):
    scene = mujoco.MjvScene(two.model, maxgeom=500)
    fields = scene_geom_fields(scene)
    camera = mujoco.MjvCamera()
    mujoco.mjv_updateScene(two.model, two.data, mujoco.MjvOption(), None, camera, mujoco.mjtCatBit.mjCAT_ALL, scene)
    geoms = scene.geoms[: scene.ngeom]
    assert scene.ngeom > 50
    assert fields["type"][: scene.ngeom].tolist() == [g.type for g in geoms]
    assert fields["objid"][: scene.ngeom].tolist() == [g.objid for g in geoms]
    assert fields["objtype"][: scene.ngeom].tolist() == [g.objtype for g in geoms]
    assert np.array_equal(fields["pos"][: scene.ngeom], [g.pos for g in geoms])
    assert np.array_equal(fields["mat"][: scene.ngeom], [g.mat.ravel() for g in geoms])
    fields["dataid"][7], fields["pos"][7] = 1234, (1, 2, 3)
    assert geoms[7].dataid == 1234 and geoms[7].pos.tolist() == [1, 2, 3]


def look_from_red(sim, distance: float) -> None:
    """Blue 1 ``distance`` metres in front of red 1, side-on, red near its goal facing the field."""
    red, blue = sim.world.robots
    red.place_robot(-2.2, 0.0, 0.0)
    blue.place_robot(-2.2 + distance, 0.0, math.pi / 2)
    mujoco.mj_forward(sim.model, sim.data)


@pytest.mark.parametrize("distance", [0.6, 1.5, 3.0, 4.2])
def test_far_robots_drawn_coarser_keep_their_outline_colours_and_labels(two, distance):
    """Red 1's camera on blue 1 at the distance: the renderer of a match (``distant`` = blue's geoms)
    against one drawing blue with MuJoCo's own shapes. Blue's geoms that are small in the
    picture become meshes of fewer facets the farther it stands; its pixels keep their geom ids
    (segmentation, hence the labels) but along some outline pixels, and its colours but in a
    few pixels."""
    look_from_red(two, distance)
    model, red, blue = two.model, *two.world.robots
    camera = red.camera
    blue_geoms = camera_geoms(model, model.body_rootid[blue._body])
    options = dict(groups=(*HEAD_CAMERA_GROUPS, BEHIND_CAMERA_GROUP), hidden=camera.own_geoms())
    coarse = Renderer(model, *camera.render_size, distant=blue_geoms, **options)
    exact = Renderer(model, *camera.render_size, **options)
    picture, reference = coarse.render(two.data, "camera"), exact.render(two.data, "camera")
    drawn = [g for g in coarse.scene.geoms[: coarse.scene.ngeom] if g.objid in set(blue_geoms.tolist())]
    meshes = [g for g in drawn if g.type == G.mjGEOM_MESH]
    body_shell = next(g for g in drawn if g.objid == model.body(blue._body).geomadr[0])
    assert body_shell.type == G.mjGEOM_ELLIPSOID  # 11 cm: more than 4.4 pixels even 4 m away
    labels, reference_labels = (
        coarse.render_segmentation(two.data, "camera"),
        exact.render_segmentation(two.data, "camera"),
    )
    coarse.close()
    exact.close()
    on_blue = np.isin(reference_labels, blue_geoms)
    assert on_blue.sum() > 60  # blue is in the picture
    if distance < 1:
        assert 0 < len(meshes) < 0.6 * len(drawn)  # near: the small parts alone coarse meshes
    else:
        assert len(meshes) > 0.8 * len(drawn)  # far: the parts but the largest (the body) coarse meshes
        facets = [model.mesh_facenum[g.dataid // 2] for g in meshes]
        assert np.mean(facets) < 150  # MuJoCo's spheres here: 16 x 10 facets, ~300 triangles
    outline = np.isin(labels, blue_geoms) != on_blue
    assert outline.sum() <= 0.06 * on_blue.sum() + 3
    assert set(np.unique(labels[on_blue & np.isin(labels, blue_geoms)])) <= set(blue_geoms.tolist())
    far_off = np.abs(picture.astype(int) - reference).max(axis=2) > 24
    assert far_off.sum() <= 0.08 * on_blue.sum() + 3


def test_parts_smaller_than_a_pixel_are_left_out(two):
    """Blue's LEDs (2-5 mm) span under a pixel from 4 m: not drawn; its body is."""
    look_from_red(two, 4.2)
    model, red, blue = two.model, *two.world.robots
    red.camera.frame()
    renderer = red.camera._renderer
    renderer.render(two.data, "camera")
    drawn = {g.objid for g in renderer.scene.geoms[: renderer.scene.ngeom]}
    names = {model.geom(g).name for g in drawn}
    assert "robot2/led_face_centre" not in names and any(name.startswith("robot2/") for name in names)
    assert model.geom("robot2/led_face_centre").id in camera_geoms(model, model.body_rootid[blue._body])
