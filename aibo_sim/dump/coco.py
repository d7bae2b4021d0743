"""Detection labels: each frame's ball, goals, beacons and robots as boxes, and the dump's
COCO annotations file built from them.

An object is a body that holds geoms of a labelled class (``geom_classes``): the ball, each
goal, each beacon, each robot other than the one carrying the camera (the observer: its own
paws, where the head looks down at them, are not a detection). Goals and beacons are drawn as
meshes merged across objects, so their labels come from each object's own geoms of the same shapes.
In a match each other robot is an object named by its spec (``red 2``, ``RobotSpec.name``), its
detection of category "robot" with its ``team`` and ``number``; in coco.json its category is its
team's (``field.TEAM_CATEGORIES``: ``robot_red``, ``robot_blue``; "robot" for a robot without a team).

A frame's objects come from segmentation renders of the head camera (``camera.segmentation``:
the picture's lens and exposure), the model's geom groups set for each render and restored:

- one with every object told apart: an object's visible pixels are those it is seen at;
  its box is their bounding box, ``[x, y, width, height]`` in COCO's pixel edges (pixel
  (i, j) spans x i .. i + 1, y j .. j + 1; its centre is at x + w / 2 - 0.5 in the camera's
  pixel-centre coordinates), ``area`` their count, ``segmentation`` their mask (``mask_rle``:
  COCO's run-length encoding, exact where polygons would fill the holes that nearer objects
  make, and read by pycocotools' ``annToMask``);
- one per visible object alone: the pixels it would cover with nothing in front of it,
  inside the image. ``visibility`` = visible pixels / those (1.0: nothing hides any of it;
  the image border cuts both alike; another robot in front hides a robot as any object does).

The renders draw what the observer's camera draws: its geom groups, the other robots whole,
never the observer's own geoms behind the lens (``camera.own_geoms``).

An object no pixel of which is seen gets no box.
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import mujoco
import numpy as np

from ..camera import HEAD_CAMERA_GROUPS
from ..camera.head import BEHIND_CAMERA_GROUP
from ..field import COCO_CATEGORIES, SEGMENTATION_CLASSES, TEAM_CATEGORIES
from ..render import geom_groups
from ..sim import Simulation
from .formats import PATHS, geom_classes, robot_roots
from .reading import LINES, META, frame_limit, read_meta, read_records

LABELLED = ("ball", "goal", "beacon", "robot")
MERGED = ("goal", "beacon")  # static objects drawn as one mesh per colour for all of them
CAMERA_GROUPS = (*HEAD_CAMERA_GROUPS, BEHIND_CAMERA_GROUP)  # what the head camera's renderer shows
HIDDEN_GROUP = next(g for g in range(mujoco.mjNGROUP) if g not in CAMERA_GROUPS)
VISIBILITY_DIGITS = 4


class _View:
    """The objects as one robot's camera sees them: the geoms its renders draw (``shown``), the
    object body of each labelled geom (``owner``; -1 none) and each object's detection fields."""

    def __init__(self, model: mujoco.MjModel, classes: np.ndarray, observer: Simulation):
        in_world = model.geom_bodyid == 0
        merged = np.isin(classes, MERGED)
        roots = model.body_rootid[model.geom_bodyid]
        # The camera's geoms (its groups, the other robots whole, not its own behind the lens),
        # the merged meshes swapped for each object's own geoms.
        drawn = np.isin(model.geom_group, CAMERA_GROUPS)
        drawn[observer.camera.own_geoms()] = False
        self.shown = drawn & ~(merged & in_world) | merged & ~in_world
        own = roots == model.body_rootid[observer._body]  # the robot carrying the camera
        labelled = self.shown & np.isin(classes, LABELLED) & ~in_world & ~own
        self.owner = np.full(model.ngeom + 1, -1)  # object body per geom; the last entry: none (id -1)
        self.owner[:-1][labelled] = roots[labelled]
        self.fields = {int(body): {"category": str(classes[g])} for g, body in enumerate(self.owner[:-1]) if body >= 0}
        robots = {root: observer.world.robots[instance - 1].spec for root, instance in robot_roots(model).items()}
        for body, fields in self.fields.items():
            spec = robots.get(body)
            if spec is None:
                fields["object"] = model.body(body).name
            else:
                fields.update(object=spec.name, team=spec.team, number=spec.number)


class Objects:
    """A model's labelled objects as the camera of ``observer`` (a robot of the world: a
    ``Simulation``, ``world.robots``) sees them, its own body never an object. A model instead
    of a robot (the world's, or the same scene compiled apart): the observer is the robot that
    ``detect`` is given (robot 1 for a lone robot, as before matches)."""

    def __init__(self, observer: Simulation | mujoco.MjModel):
        model = observer if isinstance(observer, mujoco.MjModel) else observer.model
        self.model, self.observer = model, None if observer is model else observer
        self.classes = np.array(SEGMENTATION_CLASSES)[geom_classes(model)[:-1]]
        self._views: dict[int, _View] = {}  # by the observer's body

    def view(self, observer: Simulation) -> _View:
        """The objects as ``observer``'s camera sees them (made once per observer)."""
        if observer.model.ngeom != self.model.ngeom:  # the same scene, maybe compiled twice
            raise ValueError("Objects: the robot is not in a world of this model")
        if observer._body not in self._views:
            with observer.world.render_lock:  # the geom groups, which a match camera's renders change
                self._views[observer._body] = _View(self.model, self.classes, observer)
        return self._views[observer._body]

    @staticmethod
    def _render(sim: Simulation, geoms: np.ndarray) -> np.ndarray:
        """Geom ids of the current frame with only ``geoms`` (a mask) drawn (the model's geom groups
        changed for the render's time, holding the world's render lock: a match's robots share them)."""
        shown = np.where(geoms, HEAD_CAMERA_GROUPS[0], HIDDEN_GROUP)
        with geom_groups(sim.model, slice(None), shown, sim.world.render_lock):
            return sim.camera.segmentation()

    def _as_segmented(self, view: _View, owners: np.ndarray, drawn: np.ndarray) -> np.ndarray:
        """``owners`` (object body per pixel, -1 none) with each goal's and beacon's pixels those
        the camera's segmentation shows their class at: drawn there as merged meshes, their own
        geoms rasterise apart along some edges. A pixel of the class that the own geoms leave to
        no object of it takes the nearest one's. ``drawn``: the frame's geom ids."""
        drawn_class = np.where(drawn >= 0, self.classes[drawn], "")
        result = owners.copy()
        for category in MERGED:
            ours = np.isin(owners, [body for body, fields in view.fields.items() if fields["category"] == category])
            here = drawn_class == category
            known, unknown = ours & here, here & ~ours
            result[ours & ~here] = -1
            if known.any() and unknown.any():  # labels number the known pixels in row order
                _, nearest = cv2.distanceTransformWithLabels(
                    (~known).astype(np.uint8), cv2.DIST_L2, 3, labelType=cv2.DIST_LABEL_PIXEL
                )
                result[unknown] = owners[known][nearest[unknown] - 1]
        return result

    def detect(self, sim: Simulation | None = None, ids: np.ndarray | None = None) -> list[dict]:
        """The current frame's visible objects as ``sim``'s camera sees them (default: the
        observer's): category, object (body name; a robot's spec name), for a robot its team and
        number, bbox, area, visibility, segmentation. ``ids``: the frame's ``camera.segmentation()``
        (geom ids), rendered when not given."""
        sim = sim if sim is not None else self.observer
        if sim is None:
            raise ValueError("Objects.detect: which robot's camera? (Objects was made from a model)")
        view = self.view(sim)
        drawn = sim.camera.segmentation() if ids is None else ids
        owners = self._as_segmented(view, view.owner[self._render(sim, view.shown)], drawn)
        detections = []
        for body in np.unique(owners[owners >= 0]).tolist():
            ys, xs = np.nonzero(owners == body)
            alone = self._render(sim, view.shown & (view.owner[:-1] == body))
            x, y = int(xs.min()), int(ys.min())
            detections.append(
                {
                    **view.fields[body],
                    "bbox": [x, y, int(xs.max()) - x + 1, int(ys.max()) - y + 1],
                    "area": int(xs.size),
                    "visibility": round(min(1.0, xs.size / int((alone >= 0).sum())), VISIBILITY_DIGITS),
                    "segmentation": mask_rle(owners == body),
                }
            )
        return detections


def mask_rle(mask: np.ndarray) -> dict:
    """A (h, w) boolean mask as COCO's uncompressed run-length encoding: ``size`` [h, w] and
    ``counts``, the lengths of alternating runs of 0 and 1 down the columns, left to right
    (column-major order), starting with the 0s (a first count of 0 when pixel (0, 0) is set)."""
    flat = mask.ravel(order="F")
    edges = np.flatnonzero(flat[1:] != flat[:-1]) + 1
    counts = np.diff(np.concatenate(([0], edges, [flat.size]))).tolist()
    return {"size": list(mask.shape), "counts": [0, *counts] if flat[0] else counts}


def coco_category(item: dict) -> str:
    """A detection's coco.json category: its team's for a robot in a team (``robot_red``), else its own."""
    return TEAM_CATEGORIES.get(item.get("team"), item["category"])


def coco_dataset(out: Path, folders: list[Path]) -> dict:
    """The COCO detection dataset of the dump in ``out`` whose frames lie in ``folders`` (the
    dump itself, or its shards in order): image ids 1, 2, ... in ``load_dump``'s order, file
    names the rgb files relative to ``out``, category ids the segmentation class ids, then the
    teams' robot categories (``field.COCO_CATEGORIES``). Those are listed for a match's dump
    (meta.json's ``"robots"``, ``formats.robots_meta``, or a detection with a team); a robot's
    annotation has its ``team`` and ``number``."""
    images, annotations, match = [], [], False
    for folder in folders:
        meta = read_meta(folder / META)
        match = match or "robots" in meta
        camera = meta["camera"]
        prefix = folder.relative_to(out).as_posix() + "/" if folder != out else ""
        records = {r["index"]: r for r in read_records(folder / LINES, frame_limit(meta))}
        for index in sorted(records):
            image_id = len(images) + 1
            images.append(
                {
                    "id": image_id,
                    "file_name": prefix + PATHS["rgb"].format(index=index),
                    "width": camera["width"],
                    "height": camera["height"],
                }
            )
            for item in records[index].get("objects", []):
                match = match or "team" in item
                annotations.append(
                    {
                        "id": len(annotations) + 1,
                        "image_id": image_id,
                        "category_id": COCO_CATEGORIES.index(coco_category(item)),
                        "bbox": item["bbox"],
                        "area": item["area"],
                        "iscrowd": 0,
                        "visibility": item["visibility"],
                        "object": item["object"],
                        **{key: item[key] for key in ("team", "number") if key in item},  # a match's robots
                        # the records of dumps made before masks were recorded have none
                        **({"segmentation": item["segmentation"]} if "segmentation" in item else {}),
                    }
                )
    names = (*LABELLED, *TEAM_CATEGORIES.values()) if match else LABELLED
    categories = [{"id": COCO_CATEGORIES.index(name), "name": name} for name in names]
    return {
        "info": {"description": "aibo-sim dump: head-camera detections"},
        "images": images,
        "annotations": annotations,
        "categories": categories,
    }


def coco_bytes(out: Path, folders: list[Path]) -> bytes:
    """coco.json's content (the same for the same frames, however they were written)."""
    return (json.dumps(coco_dataset(out, folders)) + "\n").encode()
