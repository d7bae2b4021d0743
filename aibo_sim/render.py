"""Headless offscreen rendering: OpenGL backend choice and a small camera renderer.

Backend: ``MUJOCO_GL`` (egl, osmesa or glfw), which ``import aibo_sim`` sets to EGL or
OSMesa when it is unset (see ``_gl.py``). A backend that cannot make a context raises
``RenderingUnavailable`` naming the system packages that provide one.

Quality: software OpenGL (Mesa llvmpipe) pays ~20x per frame for MuJoCo's default
4096^2 shadow map, so the head camera renders without shadows, reflections or
multisampling, with spheres and capsules of 16 x 10 facets (MuJoCo's default is 28 x 16;
at 208 x 160 the difference is invisible and the frame costs ~35 % less) by default
(``quality="fast"``); ``quality="high"`` keeps MuJoCo's settings with shadows for
pictures (README renders, third-person views).

Culling: MuJoCo hands every geom of the shown groups to OpenGL, and llvmpipe spends
~20 us on each even when it lies outside the picture. Without shadows and reflections a geom
whose bounding sphere is outside the camera's view frustum cannot change a pixel, so such
geoms are left out of the scene (the head camera typically draws 8 of its 30 geoms: ~0.46 ms
a frame instead of ~0.67 ms). The image is the same, bit for bit (tested).

Other robots (a match): their parts smaller than a pixel are left out too, and the small ones
drawn as coarser meshes (``lod.py``): a robot 2-4 m away costs 6-9x less, its outline within
0.15 pixels of the true one.
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import functools
import math
import os
import warnings

import cv2
import mujoco
import numpy as np

from ._gl import SYSTEM_PACKAGES, choose_gl_backend
from .lod import LevelsOfDetail

GL_RGBA, GL_UNSIGNED_BYTE, GL_RENDERER = 0x1908, 0x1401, 0x1F01
GL_PACK_INVERT_MESA = 0x8758  # Mesa's GL_MESA_pack_invert: glReadPixels gives the rows top to bottom


class RenderingUnavailable(RuntimeError):
    """No headless OpenGL backend works on this machine."""


def gl_backend() -> str:
    """The OpenGL backend to render with."""
    backend = os.environ.get("MUJOCO_GL", "").strip().lower() or choose_gl_backend()
    if not backend:
        raise RenderingUnavailable(f"no headless OpenGL library found. Install {SYSTEM_PACKAGES}, or set MUJOCO_GL.")
    return backend


def _context_class(backend: str):
    platform = os.environ.get("PYOPENGL_PLATFORM", "").strip().lower()
    if backend in ("egl", "osmesa") and platform and platform != backend:
        raise RenderingUnavailable(
            f"MUJOCO_GL={backend} and PYOPENGL_PLATFORM={platform} disagree: unset PYOPENGL_PLATFORM, "
            "or set both to egl or to osmesa"
        )
    try:
        if backend == "egl":
            from mujoco.egl import GLContext
        elif backend == "osmesa":
            from mujoco.osmesa import GLContext
        elif backend == "glfw":
            from mujoco.glfw import GLContext
        else:
            raise RenderingUnavailable(f"MUJOCO_GL={backend!r} is not one of egl, osmesa, glfw")
    except ImportError as exc:
        raise RenderingUnavailable(f"MUJOCO_GL={backend}: {exc}. Install {SYSTEM_PACKAGES}.") from exc
    return GLContext


class _EglCurrent:
    """The calling thread's current EGL context, read and restored through libEGL (ctypes):
    ``address()`` (~0.4 us) tells whether a context is already current, ``save()`` and
    ``restore(saved)`` put back whatever another renderer (Gymnasium's, ``mujoco.Renderer``)
    had current, which they assume stays so."""

    EGL_DRAW, EGL_READ = 0x3059, 0x305A

    def __init__(self):
        egl = ctypes.CDLL("libEGL.so.1")
        for name in ("eglGetCurrentContext", "eglGetCurrentDisplay"):
            getattr(egl, name).restype, getattr(egl, name).argtypes = ctypes.c_void_p, []
        egl.eglGetCurrentSurface.restype, egl.eglGetCurrentSurface.argtypes = ctypes.c_void_p, [ctypes.c_int32]
        egl.eglMakeCurrent.restype = ctypes.c_uint32
        egl.eglMakeCurrent.argtypes = [ctypes.c_void_p] * 4
        self._egl, self.address = egl, egl.eglGetCurrentContext

    def save(self) -> tuple | None:
        """(display, draw, read, context) of the current context; None when none is."""
        egl = self._egl
        context = egl.eglGetCurrentContext()
        if not context:
            return None
        return (
            egl.eglGetCurrentDisplay(),
            egl.eglGetCurrentSurface(self.EGL_DRAW),
            egl.eglGetCurrentSurface(self.EGL_READ),
            context,
        )

    def restore(self, saved: tuple) -> None:
        self._egl.eglMakeCurrent(*saved)

    def release(self) -> None:
        """Make no context current in this thread (another thread may then make it current)."""
        self._egl.eglMakeCurrent(self._egl.eglGetCurrentDisplay(), None, None, None)


class _OsmesaCurrent:
    """The same as ``_EglCurrent`` for OSMesa (libOSMesa, ctypes). OSMesa makes a context
    current with its colour buffer, whose pixel type it does not tell: the contexts restored
    are MuJoCo's (``mujoco.osmesa.GLContext``, which Gymnasium and ``mujoco.Renderer`` use),
    whose buffers are float."""

    GL_FLOAT = 0x1406

    def __init__(self):
        osmesa = ctypes.CDLL(ctypes.util.find_library("OSMesa") or "libOSMesa.so")
        osmesa.OSMesaGetCurrentContext.restype, osmesa.OSMesaGetCurrentContext.argtypes = ctypes.c_void_p, []
        pointer = ctypes.POINTER
        osmesa.OSMesaGetColorBuffer.argtypes = [
            ctypes.c_void_p,
            pointer(ctypes.c_int),
            pointer(ctypes.c_int),
            pointer(ctypes.c_int),
            pointer(ctypes.c_void_p),
        ]
        osmesa.OSMesaMakeCurrent.argtypes = [
            ctypes.c_void_p,
            ctypes.c_void_p,
            ctypes.c_uint,
            ctypes.c_int,
            ctypes.c_int,
        ]
        self._osmesa, self.address = osmesa, osmesa.OSMesaGetCurrentContext

    def save(self) -> tuple | None:
        """(context, buffer, width, height) of the current context; None when none is."""
        context = self._osmesa.OSMesaGetCurrentContext()
        if not context:
            return None
        width, height, pixel_format, buffer = ctypes.c_int(), ctypes.c_int(), ctypes.c_int(), ctypes.c_void_p()
        if not self._osmesa.OSMesaGetColorBuffer(context, width, height, pixel_format, buffer):
            return None
        return context, buffer.value, width.value, height.value

    def restore(self, saved: tuple) -> None:
        context, buffer, width, height = saved
        self._osmesa.OSMesaMakeCurrent(context, buffer, self.GL_FLOAT, width, height)

    def release(self) -> None:
        """Make no context current in this thread."""
        self._osmesa.OSMesaMakeCurrent(None, None, 0, 0, 0)


def _current_context(backend: str) -> _EglCurrent | _OsmesaCurrent | None:
    """What reads and restores the current context of ``backend`` (EGL, OSMesa); None for GLFW
    or without the library (our renderer then makes its context current every frame and
    leaves it so)."""
    try:
        return {"egl": _EglCurrent, "osmesa": _OsmesaCurrent}[backend]() if backend in ("egl", "osmesa") else None
    except (OSError, AttributeError):
        return None


def scene_geom_fields(scene: mujoco.MjvScene) -> dict[str, np.ndarray]:
    """Writable views of all the scene's geoms' ``type``, ``dataid``, ``objtype``, ``objid``
    (int32, ``(maxgeom,)``), ``pos`` ``(maxgeom, 3)`` and ``mat`` ``(maxgeom, 9)`` (float32): one
    numpy operation for what the bindings give one geom at a time. The places of the integers in
    ``mjvGeom`` (they move between MuJoCo versions) are found by writing marks through the
    bindings; the views live as long as ``scene``."""
    geoms = scene.geoms
    if len(geoms) < 3:
        raise ValueError("scene_geom_fields needs a scene of 3 geoms or more")
    size0, probe = geoms[0].size.ctypes.data, geoms[1]
    size1 = probe.size.ctypes.data
    stride = size1 - size0
    offsets = {"pos": probe.pos.ctypes.data - size1, "mat": probe.mat.ctypes.data - size1}  # bytes from size
    window = np.ctypeslib.as_array((ctypes.c_int32 * (stride // 2)).from_address(size0))  # geom 1's, around its size
    for field, mark in (("type", 0x5A17), ("dataid", 0x5A18), ("objtype", 0x5A19), ("objid", 0x5A1A)):
        saved = getattr(probe, field)
        setattr(probe, field, mark)
        found = np.flatnonzero(window == mark)
        setattr(probe, field, saved)
        if found.size != 1:
            raise RuntimeError(f"cannot find mjvGeom.{field} in this MuJoCo's scene ({mujoco.__version__})")
        offsets[field] = int(found[0]) * 4 - stride
    lengths = {"pos": 3, "mat": 9}  # float32s; the others one int32
    low, high = min(offsets.values()), max(offset + 4 * lengths.get(field, 1) for field, offset in offsets.items())
    raw = np.ctypeslib.as_array((ctypes.c_uint8 * (stride * (len(geoms) - 1) + high - low)).from_address(size0 + low))
    return {
        field: np.ndarray(
            (len(geoms), lengths[field]) if field in lengths else (len(geoms),),
            np.float32 if field in lengths else np.int32,
            raw,
            offset - low,
            (stride, 4) if field in lengths else (stride,),
        )
        for field, offset in offsets.items()
    }


@contextlib.contextmanager
def geom_groups(model: mujoco.MjModel, geoms, groups, lock=None):
    """``model.geom_group[geoms] = groups`` (ids, a mask or a slice) for the block's time, holding
    ``lock`` if given (a match's robots share the model: see ``Renderer``)."""
    with lock if lock is not None else contextlib.nullcontext():
        saved = np.array(model.geom_group[geoms])
        model.geom_group[geoms] = groups
        try:
            yield
        finally:
            model.geom_group[geoms] = saved


def _one_picture(method):
    """``method`` holding the renderer's picture lock (see ``Renderer``)."""

    @functools.wraps(method)
    def locked(self, *args):
        with self._picture_lock:
            return method(self, *args)

    return locked


class Renderer:
    """Renders RGB (and optionally depth) images of one camera of a model, offscreen.

    Shows the geom groups in ``groups`` (default 0-2: scene and visual geoms; collision
    geoms are group 3), no sites, never the geoms ``hidden`` (ids: the head camera leaves out its
    own robot's group 1, the visual geoms behind its lens, which it cannot see anyway), and the
    geoms ``distant`` (the head camera's other robots) only where their bounding sphere spans a
    pixel or more (their LEDs and screws, a pixel centre or none at a distance, cost a robot's
    worth of triangles), and as the model's coarser meshes while they are small (``lod.py``).
    ``render`` returns a new ``(height, width, 3)`` uint8 array, top row first. ``cull=False`` draws the geoms outside
    the view too (same pixels, slower); ``scene`` is the ``MjvScene`` last drawn.

    ``pinholes`` maps camera ids to the ``(cam_intrinsic, cam_sensorsize, cam_resolution)`` this
    renderer draws them with instead of the model's (a lens's picture is resampled from a pinhole
    render). ``lock`` (an RLock) is shared by the renderers of one model and data in several
    threads (a match's cameras): the model is changed only while a scene is built from it
    (culling hides geoms by their groups), holding the lock, and each renderer leaves its context
    current in no thread, so that any thread may draw it next. With a software OpenGL (Mesa's
    llvmpipe: the drawing is the CPU's work) the pictures are drawn and read outside the lock, in
    parallel (``parallel``); a GPU's driver serializes the threads anyway, at a cost (an H200: 8
    cameras' pictures in 2 threads took 1.5x the time of one thread), so there the lock is held
    for the whole picture.
    """

    def __init__(
        self,
        model: mujoco.MjModel,
        width: int,
        height: int,
        quality: str = "fast",
        groups: tuple[int, ...] = (0, 1, 2),
        cull: bool = True,
        hidden=(),
        distant=(),
        pinholes: dict[int, tuple] | None = None,
        lock=None,
    ):
        if quality not in ("fast", "high"):
            raise ValueError(f"quality must be 'fast' or 'high', not {quality!r}")
        self.width, self.height, self.model = width, height, model
        backend = gl_backend()
        self._current_context = _current_context(backend)
        other = self._current_context.save() if self._current_context is not None else None  # before ours exists
        try:
            with warnings.catch_warnings(record=True) as warned:  # GLFW's errors come as warnings
                warnings.simplefilter("always")
                gl = _context_class(backend)(width, height)  # mujoco.egl makes it current at once
            if not gl._context:  # GLFW without a display: a NULL window (and nothing for close to free)
                why = "; ".join(str(w.message) for w in warned) or "no context"
                raise RenderingUnavailable(
                    f"MUJOCO_GL={backend}: cannot create an OpenGL context ({why}); "
                    "unset MUJOCO_GL to render headless with EGL or OSMesa"
                )
            self._gl = gl
            self._context_address = (
                ctypes.cast(self._gl._context, ctypes.c_void_p).value if self._current_context is not None else None
            )
            self._gl.make_current()
            self._other_context = other
        except RenderingUnavailable:
            raise
        except Exception as exc:  # EGL/OSMesa report failures with their own exception types
            raise RenderingUnavailable(
                f"MUJOCO_GL={backend}: cannot create an OpenGL context ({exc}). Install {SYSTEM_PACKAGES}, "
                "or try another MUJOCO_GL."
            ) from exc
        # The context takes these from the model: an offscreen buffer of exactly this size
        # (MuJoCo clears all of it each frame: 640x480 for a 208x160 image cost ~20 %), and
        # in fast quality no multisampling and coarser spheres and capsules.
        built_in, buffer = model.vis.quality, model.vis.global_
        saved = built_in.offsamples, built_in.numslices, built_in.numstacks, buffer.offwidth, buffer.offheight
        buffer.offwidth, buffer.offheight = width, height
        if quality == "fast":
            built_in.offsamples, built_in.numslices, built_in.numstacks = 0, min(saved[1], 16), min(saved[2], 10)
        try:
            self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_100)
        finally:
            built_in.offsamples, built_in.numslices, built_in.numstacks, buffer.offwidth, buffer.offheight = saved
        mujoco.mjr_setBuffer(mujoco.mjtFramebuffer.mjFB_OFFSCREEN, self._context)
        self._scene = mujoco.MjvScene(model, maxgeom=4000)
        self._scene.flags[mujoco.mjtRndFlag.mjRND_SHADOW] = quality == "high"
        self._scene.flags[mujoco.mjtRndFlag.mjRND_REFLECTION] = quality == "high"
        self._option = mujoco.MjvOption()
        self._option.geomgroup[:] = [int(g in groups) for g in range(6)]
        self._option.sitegroup[:] = 0
        self._option.flags[mujoco.mjtVisFlag.mjVIS_RANGEFINDER] = 0
        self._cullable_key = self._frustum_key = None
        self._cull_inputs = model.geom_group, self._option.geomgroup, model.geom_rbound  # views, read each frame
        self._hidden_group = next((g for g in range(mujoco.mjNGROUP) if g not in groups), None)
        self._cull = cull
        self._pinholes = pinholes or {}
        self._release = lock is not None and self._current_context is not None
        self._hidden = np.asarray(hidden, np.intp)
        self._distant = np.zeros(model.ngeom, bool)
        self._distant[np.asarray(distant, np.intp)] = True
        from . import scene_kernels  # numba, loaded by the first renderer rather than by every import of aibo_sim

        self._kernels = scene_kernels
        self._sorted = np.empty(model.ngeom, np.intp), np.empty(model.ngeom, np.intp), np.empty(model.ngeom)
        self._lod = LevelsOfDetail(model, np.flatnonzero(self._distant))
        self._geom_fields = scene_geom_fields(self._scene) if self._lod.geoms.size else None
        if self._hidden.size and self._hidden_group is None:
            raise ValueError("hidden geoms need a group that is not shown (groups shows them all)")
        self._multisampled = quality == "high" and saved[0] > 0
        self._rgba = np.empty((height, width, 4), np.uint8)
        self._rgba.flags.writeable = False  # handed out; only glReadPixels writes it
        self._rgba_address = ctypes.c_void_p(self._rgba.ctypes.data)
        self._gl_read, self._rows_down, software = self._gl_functions()
        self.parallel = lock is not None and software
        unlocked = contextlib.nullcontext()
        self._picture_lock = unlocked if lock is None or self.parallel else lock
        self._scene_lock = lock if self.parallel else unlocked
        self._leave()
        self._camera = mujoco.MjvCamera()
        self._rect = mujoco.MjrRect(0, 0, width, height)
        self._rgb = np.empty((height, width, 3), np.uint8)
        self._depth = np.empty((height, width), np.float32)

    def _draw(self, data: mujoco.MjData, camera: int | str | mujoco.MjvCamera) -> None:
        if isinstance(camera, mujoco.MjvCamera):
            cam = camera
        else:
            cam = self._camera
            cam.type = mujoco.mjtCamera.mjCAMERA_FIXED
            cam.fixedcamid = camera if isinstance(camera, int) else self.model.camera(camera).id
        # eglMakeCurrent through PyOpenGL: ~5 us, ~20 us right after a physics step; the check ~0.4 us.
        self._enter()
        pinhole = self._pinholes.get(cam.fixedcamid) if cam.type == mujoco.mjtCamera.mjCAMERA_FIXED else None
        with self._scene_lock, self._lens(pinhole, cam.fixedcamid):
            culled, distant = self._outside_view(data, cam)
            if self._hidden.size:
                culled = np.concatenate((culled, self._hidden))
            with geom_groups(self.model, culled, self._hidden_group):
                mujoco.mjv_updateScene(
                    self.model, data, self._option, None, cam, mujoco.mjtCatBit.mjCAT_ALL, self._scene
                )
        if self._geom_fields is not None and distant is not None:
            self._lod.apply(self._geom_fields, self._scene.ngeom, *distant)
        mujoco.mjr_render(self._rect, self._scene, self._context)

    @contextlib.contextmanager
    def _lens(self, pinhole: tuple | None, camera: int):
        """The model's ``camera`` with the intrinsics of ``pinhole`` (if any) for the block's time."""
        if pinhole is None:
            yield
            return
        model = self.model
        saved = (
            model.cam_intrinsic[camera].copy(),
            model.cam_sensorsize[camera].copy(),
            model.cam_resolution[camera].copy(),
        )
        model.cam_intrinsic[camera], model.cam_sensorsize[camera], model.cam_resolution[camera] = pinhole
        try:
            yield
        finally:
            model.cam_intrinsic[camera], model.cam_sensorsize[camera], model.cam_resolution[camera] = saved

    def _enter(self) -> None:
        """Make this renderer's context current, remembering another renderer's (EGL)."""
        self._other_context = None
        if self._current_context is None:
            self._gl.make_current()
        elif self._current_context.address() != self._context_address:
            self._other_context = self._current_context.save()
            self._gl.make_current()

    def _leave(self) -> None:
        """Make current again the context another renderer had before ``_enter``: the process is
        left as found (Gymnasium's renderers assume their context stays current)."""
        if self._other_context is not None:
            self._current_context.restore(self._other_context)
            self._other_context = None
        elif self._release:
            self._current_context.release()

    def _read(self, rgb: np.ndarray | None, depth: np.ndarray | None) -> None:
        mujoco.mjr_readPixels(rgb, depth, self._rect, self._context)
        self._leave()

    def _gl_functions(self):
        """PyOpenGL's raw ``glPixelStorei`` and ``glReadPixels`` (imported once the context
        exists: MuJoCo chose PyOpenGL's platform), whether the driver reads rows top to bottom
        (``GL_PACK_INVERT_MESA`` accepted) and whether it draws in software (Mesa's llvmpipe or
        softpipe); called with this renderer's context current."""
        from OpenGL.error import GLError
        from OpenGL.raw.GL.VERSION.GL_1_0 import glGetError, glGetString, glPixelStorei, glReadPixels

        name = (ctypes.cast(glGetString(GL_RENDERER), ctypes.c_char_p).value or b"").decode("ascii", "replace")
        software = any(word in name for word in ("llvmpipe", "softpipe", "swrast"))

        for _ in range(8):  # errors left by others (GL keeps one per kind): PyOpenGL would raise them
            if not glGetError():
                break
        try:
            glPixelStorei(GL_PACK_INVERT_MESA, 0)
            rows_down = True
        except GLError:  # GL_INVALID_ENUM: a driver without the extension
            rows_down = False
        return (glPixelStorei, glReadPixels), rows_down, software

    def _read_rgba(self) -> np.ndarray:
        """The drawn picture, (h, w, 4) RGBA rows top to bottom, in the renderer's own buffer (the
        next read overwrites it; a copy where the driver cannot read rows top to bottom). One
        ``glReadPixels`` in the framebuffer's own format: ~5 us at 214x165 on llvmpipe, where
        MuJoCo's RGB read (~23 us) converts each pixel. Not for multisampled buffers (MuJoCo's
        read resolves them first)."""
        store, read = self._gl_read
        if self._rows_down:
            store(GL_PACK_INVERT_MESA, 1)
        read(0, 0, self.width, self.height, GL_RGBA, GL_UNSIGNED_BYTE, self._rgba_address)
        if self._rows_down:
            store(GL_PACK_INVERT_MESA, 0)
        self._leave()
        return self._rgba if self._rows_down else cv2.flip(self._rgba, 0)

    @property
    def scene(self) -> mujoco.MjvScene:
        """The MuJoCo scene the renderer draws (its flags and geoms)."""
        return self._scene

    def _outside_view(self, data: mujoco.MjData, cam: mujoco.MjvCamera) -> tuple[np.ndarray, tuple | None]:
        """Ids of the shown geoms whose bounding spheres lie outside the view frustum, with the
        ``distant`` geoms smaller than a pixel; and the shown ``distant`` geoms' ids, depths (m)
        and the pixels a metre spans at 1 m (for ``LevelsOfDetail.apply``), None without any.
        None and None when culling is off, shadows or reflections are on (a geom out of view can
        still cast or mirror), every group is shown (no group left to hide them in) or the camera
        is orthographic."""
        flags = self._scene.flags
        if (
            not self._cull
            or self._hidden_group is None
            or flags[mujoco.mjtRndFlag.mjRND_SHADOW]
            or flags[mujoco.mjtRndFlag.mjRND_REFLECTION]
        ):
            return np.empty(0, np.intp), None
        shown, radius = self._cullable_geoms()
        mujoco.mjv_updateCamera(self.model, data, cam, self._scene)
        eye = mujoco.mjv_averageCamera(*self._scene.camera)  # the two stereo eyes sit ipd apart; mono draws their mean
        if eye.orthographic:  # a box, not a frustum: draw everything
            return np.empty(0, np.intp), None
        normals, offsets = self._frustum_planes(eye)
        # In world axes: the camera's right, up and forward axes times the camera-axes normals
        # (right = forward x up in Python floats: np.cross costs more than the arithmetic).
        f, u = eye.forward.tolist(), eye.up.tolist()
        r = [f[1] * u[2] - f[2] * u[1], f[2] * u[0] - f[0] * u[2], f[0] * u[1] - f[1] * u[0]]
        world_normals = np.array([r, u, f]).T @ normals
        pixels_per_metre = self.height * eye.frustum_near / (eye.frustum_top - eye.frustum_bottom)  # at 1 m
        culled, far, far_depth = self._sorted
        culled_count, far_count = self._kernels.outside_view(
            data.geom_xpos,
            shown,
            radius,
            world_normals,
            offsets,
            eye.pos.astype(np.float64),
            self._distant,
            pixels_per_metre,
            eye.frustum_near,
            culled,
            far,
            far_depth,
        )
        if not far_count:
            return culled[:culled_count], None
        return culled[:culled_count], (far[:far_count], far_depth[:far_count], pixels_per_metre)

    def _frustum_planes(self, eye: mujoco.MjvGLCamera) -> tuple[np.ndarray, np.ndarray]:
        """Inward unit normals (columns, in the camera's right-up-forward axes) and offsets of
        the view frustum's left, right, bottom, top, near and far planes: a point p (relative
        to the eye, in those axes) is inside when ``p @ normals + offsets >= 0`` everywhere.
        Cached while the frustum keeps its shape."""
        near, far, centre = eye.frustum_near, eye.frustum_far, eye.frustum_center
        half_width = eye.frustum_width or 0.5 * (eye.frustum_top - eye.frustum_bottom) * self.width / self.height
        key = (near, far, centre, half_width, eye.frustum_bottom, eye.frustum_top)
        if self._frustum_key != key:
            # Each side plane passes through the eye, its slope the tangent of the edge's angle.
            left, right = (centre - half_width) / near, (centre + half_width) / near
            bottom, top = eye.frustum_bottom / near, eye.frustum_top / near
            normals = [(1, 0, -left), (-1, 0, right), (0, 1, -bottom), (0, -1, top)]
            normals = [[c / math.hypot(1, slope) for c in n] for n, slope in zip(normals, (left, right, bottom, top))]
            self._frustum = np.array([*normals, (0, 0, 1), (0, 0, -1)]).T, np.array([0, 0, 0, 0, -near, far])
            self._frustum_key = key
        return self._frustum

    def _cullable_geoms(self) -> tuple[np.ndarray, np.ndarray]:
        """Ids of the geoms in the shown groups with a finite bounding sphere (planes have
        radius 0), and their radii; cached while groups and radii stay the same."""
        group, shown_groups, radius = self._cull_inputs
        key = group.tobytes() + shown_groups.tobytes() + radius.tobytes()
        if self._cullable_key != key:
            shown = np.flatnonzero(shown_groups[group] & (radius > 0))
            self._cullable = shown, radius[shown]
            self._cullable_key = key
        return self._cullable

    @_one_picture
    def render(self, data: mujoco.MjData, camera: int | str | mujoco.MjvCamera) -> np.ndarray:
        """RGB image of ``camera`` (id, name or free MjvCamera) in the state ``data``."""
        self._draw(data, camera)
        if self._multisampled:
            self._read(self._rgb, None)
            return self._rgb[::-1].copy()
        return cv2.cvtColor(self._read_rgba(), cv2.COLOR_RGBA2RGB)

    @_one_picture
    def render_rgba(self, data: mujoco.MjData, camera: int | str | mujoco.MjvCamera) -> np.ndarray:
        """``render``'s picture as RGBA (alpha 255), read-only; without multisampling (``fast``
        quality) the renderer's own buffer, valid until its next render."""
        if self._multisampled:
            picture = cv2.cvtColor(self.render(data, camera), cv2.COLOR_RGB2RGBA)
        else:
            self._draw(data, camera)
            picture = self._read_rgba()
        picture.flags.writeable = False
        return picture

    @_one_picture
    def render_depth(self, data: mujoco.MjData, camera: int | str) -> np.ndarray:
        """Depth along the optical axis in metres, float32 ``(height, width)``."""
        self._draw(data, camera)
        self._read(None, self._depth)
        extent = self.model.stat.extent
        near, far = self.model.vis.map.znear * extent, self.model.vis.map.zfar * extent
        z = self._depth[::-1].astype(np.float64)
        return (near * far / (far - z * (far - near))).astype(np.float32)

    @_one_picture
    def render_segmentation(self, data: mujoco.MjData, camera: int | str) -> np.ndarray:
        """Geom id of every pixel, int32 ``(height, width)``; -1 where no geom is drawn.

        MuJoCo paints each scene geom in a flat colour that encodes its index in the scene
        plus one (0: nothing drawn). Exact without multisampling (``quality="fast"``); with
        it, blended edge colours may decode to wrong ids.
        """
        flags = self._scene.flags
        segment, id_colour = mujoco.mjtRndFlag.mjRND_SEGMENT, mujoco.mjtRndFlag.mjRND_IDCOLOR
        saved = flags[segment], flags[id_colour]
        flags[segment] = flags[id_colour] = True
        try:
            self._draw(data, camera)
        finally:
            flags[segment], flags[id_colour] = saved
        self._read(self._rgb, None)
        colour = self._rgb[::-1].astype(np.int32)
        scene_index_plus_one = colour[..., 0] | colour[..., 1] << 8 | colour[..., 2] << 16
        drawn = self._scene.geoms[: self._scene.ngeom]
        geom_ids = np.full(len(drawn) + 2, -1, np.int32)  # the last entry catches colours beyond the scene
        for geom in drawn:
            if geom.objtype == mujoco.mjtObj.mjOBJ_GEOM:
                geom_ids[geom.segid + 1] = geom.objid
        return geom_ids[np.minimum(scene_index_plus_one, len(drawn) + 1)]

    def close(self) -> None:
        """Free the OpenGL context and MuJoCo's rendering context; a second call does nothing."""
        if self._gl is not None:
            self._enter()  # the GL objects freed are this context's
            self._context.free()
            self._gl.free()
            self._gl = None
            self._leave()

    def __del__(self):
        try:
            self.close()
        except Exception:  # interpreter shutdown: GL may already be gone
            pass


def check_rendering(model: mujoco.MjModel) -> None:
    """RenderingUnavailable now, before a command writes anything, where ``model`` cannot be
    rendered (no OpenGL context: ``MUJOCO_GL=glfw`` without a display)."""
    Renderer(model, 1, 1).close()
