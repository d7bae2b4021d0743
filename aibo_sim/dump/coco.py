"""Detection labels: each frame's ball, goals, beacons and robots as boxes, and the dump's
COCO annotations file built from them.

An object is a body that holds geoms of a labelled class (``geom_classes``): the ball, each
goal, each beacon, each robot other than the one carrying the camera (its own paws, where the
head looks down at them, are not a detection). Goals and beacons are drawn as meshes merged across objects, so
their labels come from each object's own geoms of the same shapes.

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
  the image border cuts both alike).

An object no pixel of which is seen gets no box.
"""

from __future__ import annotations

import json
from pathlib import Path

import mujoco
import numpy as np

from ..camera import HEAD_CAMERA_GROUPS
from ..field import SEGMENTATION_CLASSES
from ..sim import Simulation
from .formats import PATHS, geom_classes
from .reading import LINES, META, frame_limit, read_meta, read_records

LABELLED = ("ball", "goal", "beacon", "robot")
MERGED = ("goal", "beacon")  # static objects drawn as one mesh per colour for all of them
HIDDEN_GROUP = next(g for g in range(mujoco.mjNGROUP) if g not in HEAD_CAMERA_GROUPS)
VISIBILITY_DIGITS = 4


class Objects:
    """A model's labelled objects: which geoms draw them, which object each geom belongs to
    (the same for every simulation of the model)."""

    def __init__(self, model: mujoco.MjModel):
        classes = np.array(SEGMENTATION_CLASSES)[geom_classes(model)[:-1]]
        in_world = model.geom_bodyid == 0
        merged = np.isin(classes, MERGED)
        drawn = np.isin(model.geom_group, HEAD_CAMERA_GROUPS)
        # The camera's geoms, the merged meshes swapped for each object's own geoms.
        self.shown = drawn & ~(merged & in_world) | merged & ~in_world
        own = model.body_rootid[model.geom_bodyid] == model.body("body").id  # the robot carrying the camera
        labelled = self.shown & np.isin(classes, LABELLED) & ~in_world & ~own
        self.owner = np.full(model.ngeom + 1, -1)  # object body per geom; the last entry: none (id -1)
        self.owner[:-1][labelled] = model.body_rootid[model.geom_bodyid[labelled]]
        self.category = {int(body): str(classes[g]) for g, body in enumerate(self.owner[:-1]) if body >= 0}
        self.name = {body: model.body(body).name for body in self.category}

    @staticmethod
    def _render(sim: Simulation, geoms: np.ndarray) -> np.ndarray:
        """Geom ids of the current frame with only ``geoms`` (a mask) drawn."""
        group = sim.model.geom_group
        saved = group.copy()
        group[:] = np.where(geoms, HEAD_CAMERA_GROUPS[0], HIDDEN_GROUP)
        try:
            return sim.camera.segmentation()
        finally:
            group[:] = saved

    def detect(self, sim: Simulation) -> list[dict]:
        """The current frame's visible objects: category, object (body name), bbox, area, visibility."""
        owners = self.owner[self._render(sim, self.shown)]
        detections = []
        for body in np.unique(owners[owners >= 0]).tolist():
            ys, xs = np.nonzero(owners == body)
            alone = self._render(sim, self.shown & (self.owner[:-1] == body))
            x, y = int(xs.min()), int(ys.min())
            detections.append(
                {
                    "category": self.category[body],
                    "object": self.name[body],
                    "bbox": [x, y, int(xs.max()) - x + 1, int(ys.max()) - y + 1],
                    "area": int(xs.size),
                    "visibility": round(xs.size / int((alone >= 0).sum()), VISIBILITY_DIGITS),
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


def coco_dataset(out: Path, folders: list[Path]) -> dict:
    """The COCO detection dataset of the dump in ``out`` whose frames lie in ``folders`` (the
    dump itself, or its shards in order): image ids 1, 2, ... in ``load_dump``'s order, file
    names the rgb files relative to ``out``, category ids the segmentation class ids."""
    images, annotations = [], []
    for folder in folders:
        meta = read_meta(folder / META)
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
                annotations.append(
                    {
                        "id": len(annotations) + 1,
                        "image_id": image_id,
                        "category_id": SEGMENTATION_CLASSES.index(item["category"]),
                        "bbox": item["bbox"],
                        "area": item["area"],
                        "iscrowd": 0,
                        "visibility": item["visibility"],
                        "object": item["object"],
                        # the records of dumps made before masks were recorded have none
                        **({"segmentation": item["segmentation"]} if "segmentation" in item else {}),
                    }
                )
    categories = [{"id": SEGMENTATION_CLASSES.index(name), "name": name} for name in LABELLED]
    return {
        "info": {"description": "aibo-sim dump: head-camera detections"},
        "images": images,
        "annotations": annotations,
        "categories": categories,
    }


def coco_bytes(out: Path, folders: list[Path]) -> bytes:
    """coco.json's content (the same for the same frames, however they were written)."""
    return (json.dumps(coco_dataset(out, folders)) + "\n").encode()
