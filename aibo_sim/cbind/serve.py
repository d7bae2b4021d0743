"""Running a compiled controller as a child process and answering its calls.

Each call is made on the Python API (``aibo_sim.controller``) with the installed robot, so a
C controller gets the values, the semantics and the errors a Python controller gets; the
answers of reading calls (``PREFETCHED``) also go ahead with each step's. The process runs
under ``child.Child``'s discipline: a process group of its own, killed with aibo-sim (even by
SIGKILL) and, with whatever it started, at the end of the run. How it ends, as the runner
reports it:

- the run's duration is over: ``robot_step`` answers "end", the controller runs its
  ``robot_die`` functions and exits 0 (``SimulationEnd`` here); it returns from ``main`` or
  calls ``exit(0)``: the run ends there;
- Ctrl-C or SIGTERM: acted on between two calls, never in the middle of reading or answering
  one (which would lose a call, and leave both sides waiting for the other): its next
  ``robot_step`` is answered "end", its ``robot_die`` functions run, then the signal acts here
  as it would have (``KeyboardInterrupt``, ``cli.Terminated``: exit status 130, 143). A
  controller that makes no call for ``child.GRACE_S`` after the signal (it computes) is
  stopped without them; a second signal acts at once (a ``robot_die`` function that never
  returns);
- ``exit(N)``, N not 0: ``SystemExit(N)``, as a Python controller's ``sys.exit(N)``;
- a call raised (an unknown device, a bad value): the controller's calls after it are not made
  (a Python controller raised there), its next call that waits is answered "failed", its
  ``robot_die`` functions run (a call of theirs that fails ends that one), then
  ``CControllerError`` names the call and the error, and those of the ``robot_die`` functions;
- it crashed (a signal: segmentation fault, abort): ``CControllerError`` names the signal;
- the binding could not go on (it closed its socket, then made a call; a call from a second
  thread; a call too large): ``CControllerError`` gives the reason ``libaibo.c`` leaves in the
  shared file, past the images (not its ``exit(70)``).

A controller that computes for long between two calls leaves the simulated time where it
is; after ``WAIT_NOTICE_S`` of wall time without a call, one line on stderr says that the
simulator is waiting for the controller (simulated time and how long), so such a controller
is not taken for a simulator that hangs (``runner`` says the same of a Python controller).
"""

from __future__ import annotations

import contextlib
import io
import mmap
import os
import signal
import socket
import struct
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from .. import controller as api
from ..mtn import MtnError
from ..render import RenderingUnavailable
from ..robot import SimulationEnd, deleted_motion_error
from ..sim import SimulationDiverged
from .child import Child
from .protocol import MAX_ANSWER_BYTES, MAX_IMAGE_BYTES, MAX_REASON_BYTES, OPS, PREFETCHED, STATUS

WAIT_NOTICE_S = 10.0
SPIN_S = 0.002  # how long this process polls for the controller's next call before it sleeps
_OP, _LENGTH, _AHEAD = struct.Struct("<i"), struct.Struct("<I"), struct.Struct("<iiI")


class CControllerError(RuntimeError):
    """A C controller's call failed (at simulated ``time_ms``), or the controller crashed."""

    def __init__(self, message: str, time_ms: int | None = None):
        super().__init__(message)
        self.time_ms = time_ms


class _Motions:
    """The MTN handles a controller holds: numbers 1, 2, ... for what ``mtn_new`` returned (never
    reused: a number up to the last one made that is not held was deleted)."""

    def __init__(self):
        self._by_id: dict[int, object] = {}
        self._last = 0

    def new(self, filename: str) -> int:
        motion = api.mtn_new(filename)
        if motion is None:
            return 0
        self._last += 1
        self._by_id[self._last] = motion
        return self._last

    def delete(self, handle: int) -> None:
        """``mtn_delete``: the motion stops and its handle is no longer one."""
        api.mtn_delete(self.get(handle, "mtn_delete"))
        self._by_id.pop(handle, None)

    def get(self, handle: int, function: str):
        """The motion of ``handle``: None for 0 (NULL: a failed ``mtn_new``, which the API reports
        as such); MtnError for a deleted one or a number ``mtn_new`` did not return."""
        if handle == 0 or handle in self._by_id:
            return self._by_id.get(handle)
        if 0 < handle <= self._last:
            raise deleted_motion_error(function)
        raise MtnError(None, None, f"{function}({handle:#x}): not an MTN (use the value mtn_new returned)")


def _handlers(image: memoryview) -> dict:
    """The Python side of each call in ``OPS``, by name."""
    motions = _Motions()

    def camera_get_image(tag):
        pixels = np.ascontiguousarray(api.camera_get_image(tag), np.uint8).reshape(-1)
        image[: pixels.size] = pixels
        return api.camera_get_width(tag), api.camera_get_height(tag)

    def mtn_fprint(handle):
        text = io.StringIO()
        api.mtn_fprint(text, motions.get(handle, "mtn_fprint"))
        return text.getvalue()

    def on_motion(name):
        function = getattr(api, name)
        return lambda handle: function(motions.get(handle, name))

    handlers = {name: getattr(api, name) for name, _, _ in OPS if hasattr(api, name)}
    handlers.update(
        {
            name: on_motion(name)
            for name in ("mtn_play", "mtn_is_over", "mtn_get_length", "mtn_get_time", "mtn_get_name")
        }
    )
    handlers.update(
        {
            "camera_get_image": camera_get_image,
            "camera_save_image": lambda tag, folder, name, quality: api.camera_save_image(
                tag, name, quality, folder=folder or None
            ),
            "mtn_new": motions.new,
            "mtn_delete": motions.delete,
            "mtn_fprint": mtn_fprint,
            "mtn_get_error": lambda: api.mtn_get_error() or "",
        }
    )
    return handlers


class _Call:
    """One call of ``OPS``: the Python function that answers it, how its arguments are read and
    its answer written (precompiled: the binding's cost is mostly this, per call)."""

    END = struct.pack("<Ii", 4, STATUS["end"])
    FAILED = struct.pack("<Ii", 4, STATUS["failed"])

    def __init__(self, name: str, arguments: str, results: str, function):
        self.name, self.function, self.results = name, function, results
        self.ahead = name in PREFETCHED
        self._kinds = arguments
        self._arguments = None if "s" in arguments else struct.Struct("<i" + arguments)
        self._answer = None if results in ("", "s") else struct.Struct("<Ii" + ("ii" if results == "m" else results))

    def arguments(self, payload: bytes) -> tuple:
        if self._arguments is not None:
            return self._arguments.unpack(payload)[1:]
        values, offset = [], _OP.size
        for kind in self._kinds:  # a call with a string (rare): read in turn
            if kind == "s":
                size = _LENGTH.unpack_from(payload, offset)[0]
                values.append(payload[offset + 4 : offset + 4 + size].decode("utf-8", "surrogateescape"))
                offset += 4 + size
            else:
                values += struct.unpack_from("<" + kind, payload, offset)
                offset += struct.calcsize(kind)
        return tuple(values)

    def answer(self, result) -> bytes:
        if self.results == "s":  # a motion's name is the file's bytes (latin-1), the rest UTF-8
            text = str(result).encode("latin-1" if self.name == "mtn_get_name" else "utf-8")
            return struct.pack("<IiI", 8 + len(text), STATUS["ok"], len(text)) + text
        values = result if self.results in ("m", "ddd") else (result,)
        return self._answer.pack(self._answer.size - 4, STATUS["ok"], *values)


class _Calls:
    """The calls arriving from the controller, read in bulk (calls without results come
    queued, several to a read)."""

    def __init__(self, channel: socket.socket, name: str, robot, child: Child):
        self._channel, self._name, self._robot, self._child = channel, name, robot, child
        self._buffer = bytearray()

    def next(self) -> bytes | None:
        """The next call's payload, or None when the controller has closed its end or exited."""
        buffer = self._buffer
        while len(buffer) < 4 or len(buffer) < 4 + _LENGTH.unpack_from(buffer)[0]:
            chunk = self._read()
            if not chunk:
                return None
            buffer += chunk
        size = _LENGTH.unpack_from(buffer)[0]
        payload = bytes(buffer[4 : 4 + size])
        del buffer[: 4 + size]
        return payload

    def _read(self) -> bytes:
        """What the controller sent next. Polls for ``SPIN_S`` first, yielding the core
        between polls: a controller's next call mostly comes within microseconds, and a process
        that sleeps wakes up slowly on a virtual machine."""
        deadline = time.perf_counter() + SPIN_S
        while time.perf_counter() < deadline:
            try:
                return self._channel.recv(1 << 16, socket.MSG_DONTWAIT)
            except BlockingIOError:
                os.sched_yield()
            except ConnectionResetError:  # it exited with an answer unread: gone all the same
                return b""
        if not self._child.wait(self._channel, WAIT_NOTICE_S, self.announce_wait):
            return b""  # it has exited
        try:
            return self._channel.recv(1 << 16)
        except ConnectionResetError:
            return b""

    def announce_wait(self, waited_s: float) -> None:
        announce_wait(self._name, waited_s, self._robot.time_ms)


def announce_wait(name: str, waited_s: float, time_ms: int) -> None:
    """The line that says the simulator waits for controller ``name`` (C here, Python in ``runner``)."""
    print(
        f"aibo-sim: waiting for controller {name}: no API call for {waited_s:.1f} s of wall time "
        f"(simulated time stays at t = {time_ms / 1000:.3f} s)",
        file=sys.stderr,
        flush=True,
    )


def run_c_controller(executable: Path, name: str) -> None:
    """Run ``executable`` in the working folder, answering its calls on the installed robot,
    until it exits; raises as the module docstring says."""
    robot = api.current_robot()
    with tempfile.NamedTemporaryFile(prefix="aibo-sim-images-") as shared:
        shared.truncate(MAX_IMAGE_BYTES)
        image = mmap.mmap(shared.fileno(), MAX_IMAGE_BYTES)
        ours, theirs = socket.socketpair()
        environment = {**os.environ, "AIBO_SIM_FD": str(theirs.fileno()), "AIBO_SIM_SHM": shared.name}
        child = Child(
            [str(executable)],
            name=f"controller {name}",
            pass_fds=(theirs.fileno(),),
            env=environment,
            grace_note="its robot_die functions could not run",
        )

        def binding_reason() -> str:
            """What the binding left past the images: why it ended the controller, or ''."""
            left = os.pread(shared.fileno(), MAX_REASON_BYTES, MAX_IMAGE_BYTES)
            return left.split(b"\0", 1)[0].decode("utf-8", "replace")

        try:
            with child, memoryview(image) as view:
                theirs.close()
                try:
                    _Server(ours, view, name, robot, child, binding_reason).serve()
                except SimulationEnd:
                    if child.pending is None:
                        raise
        finally:
            theirs.close()
            ours.close()
            image.close()
        reason = binding_reason()
    if reason:
        raise CControllerError(reason)
    status = child.returncode
    if status < 0:
        signal_name = signal.Signals(-status).name
        raise CControllerError(f"crashed ({signal_name}: {signal.strsignal(-status)})")
    if status:
        raise SystemExit(status)


class _Server:
    """Answers one controller's calls: its motions, the calls it sent and those read ahead, and
    whether it waits for an answer now."""

    def __init__(self, channel: socket.socket, image: memoryview, name: str, robot, child: Child, binding_reason):
        handlers = _handlers(image)
        self._table = [_Call(op_name, arguments, results, handlers[op_name]) for op_name, arguments, results in OPS]
        self._channel, self._calls, self._robot = channel, _Calls(channel, name, robot, child), robot
        self._wanted = {}  # the PREFETCHED calls made so far, by (number, arguments): answered with each step
        self._child, self._binding_reason = child, binding_reason

    def serve(self) -> None:
        """Answer the controller's calls until it exits; SimulationEnd after a run that ended.
        Once a signal is pending, every ``robot_step`` is answered "end" (the controller's
        robot_die functions run, then it exits)."""
        ended, failure, dying, skipping = False, None, [], False
        while (payload := self._calls.next()) is not None:
            number = _OP.unpack_from(payload)[0]
            if not 0 <= number < len(self._table):
                raise CControllerError(f"unknown call number {number} (a controller built against other headers?)")
            call = self._table[number]
            args = call.arguments(payload)
            self._child.stop_if_overdue()
            if skipping:  # after a call that failed, until the call that waits: made by no Python controller
                if call.results:
                    self._send(_Call.FAILED)
                    skipping = False
                continue
            if self._child.pending is not None and call.name == "robot_step":
                self._send(_Call.END)
                continue
            if call.ahead:
                self._wanted[number, args] = call
            elif call.name == "mtn_delete":  # its motion's calls are no longer answered ahead
                self._wanted = {
                    k: c for k, c in self._wanted.items() if not (c.name.startswith("mtn_") and k[1] == args)
                }
            try:
                result = call.function(*args)
            except SimulationEnd:
                ended = True
                self._send(_Call.END)
                continue
            except (SimulationDiverged, RenderingUnavailable):  # the simulator's failures, not the controller's
                raise
            except Exception as exc:
                shown = ", ".join(repr(a) for a in args)
                error = f"{call.name}({shown}) raised {type(exc).__name__}: {exc}"
                if failure is None and not ended and not self._binding_reason():
                    failure = CControllerError(error, self._robot.time_ms)
                    failure.__cause__ = exc
                else:  # in a robot_die function, which ends there (after the binding's refusal too)
                    dying.append(error)
                if call.results:
                    self._send(_Call.FAILED)
                else:
                    skipping = True
                continue
            if call.results:
                self._send(
                    _with_answers_ahead(call.answer(result), self._wanted)
                    if call.name == "robot_step"
                    else call.answer(result)
                )
        self._child.wait(None, WAIT_NOTICE_S, self._calls.announce_wait)  # it may run on after closing its socket
        if failure is not None or dying:
            reason = self._binding_reason()
            first = [str(failure)] if failure else [reason] if reason else []
            errors = first + [f"its robot_die function's call {e}" for e in dying]
            status = self._child.stop()
            if status < 0:
                errors.append(f"it crashed in a robot_die function ({signal.Signals(-status).name})")
            elif status not in (0, 1):  # 1: its way out after the failed call
                errors.append(f"a robot_die function exited with exit({status})")
            time_ms, cause = (failure.time_ms, failure.__cause__) if failure else (None, None)
            raise CControllerError("\nthen ".join(errors), time_ms) from cause
        if ended and self._child.stop() == 0:
            raise SimulationEnd()

    def _send(self, answer: bytes) -> None:
        """Send an answer; a controller that exited without reading it is found by the next read
        (the binding may have left its reason: ``run_c_controller`` reads it)."""
        with contextlib.suppress(BrokenPipeError, ConnectionResetError):
            self._channel.sendall(answer)


def _with_answers_ahead(answer: bytes, wanted: dict) -> bytes:
    """``robot_step``'s answer followed by the answers of the ``wanted`` calls (``PREFETCHED``) in
    the state it left, as many as the controller's buffer takes; a call that raises or does not
    fit is left out (the controller makes it, and gets the error or the answer)."""
    parts, room = [], MAX_ANSWER_BYTES - len(answer)
    for (number, args), call in wanted.items():
        try:
            results = call.answer(call.function(*args))[8:]
        except Exception:
            continue
        part = _AHEAD.pack(number, args[0] if args else 0, len(results)) + results
        if len(part) > room:
            break
        parts.append(part)
        room -= len(part)
    payload = answer[4:] + b"".join(parts)
    return _LENGTH.pack(len(payload)) + payload
