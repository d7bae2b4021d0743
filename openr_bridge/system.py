"""An OPEN-R system: objects connected as a memory stick's CONNECT.CFG says.

The objects' stub.cfg files are known to the system (by default ``OVirtualRobotComm`` and the
wrapper ``Controller``, both shipped in ``data/``); the memory stick only brings
CONNECT.CFG. Every connection must name a service of a known object, or ``ConfigError``
names the line: object names are case-sensitive in OPEN-R, so the report's spelling
``OvirtualRobotComm`` (a typo for ``OVirtualRobotComm``) is rejected with a hint.

The system also owns the primitives its objects open through ``OPENR::`` (``primitive.py``):
the head camera's, ``system.camera`` (an ``OCameraPrimitive``: white balance, gain and shutter,
with listeners told of each change). ``system.OPENR`` is the ``OPENR::`` API over them; every
object gets it as its ``OPENR`` attribute before ``DoStart``, as an OPEN-R object links
against libOPENR.
"""

from pathlib import Path

from .config import Connection, ServiceName, cut, find_connect_cfg, load_connect_cfg
from .errors import ConfigError
from .primitive import OPENR, OCameraPrimitive
from .wiring import DATA_DIR, OObject, OVirtualRobotComm
from .wrapper import CAMERA_CONNECTION, IMAGE_SERVICE, Controller

DEFAULT_MEMORY_STICK = DATA_DIR / "ms"


class OpenRSystem:
    """OPEN-R objects connected by CONNECT.CFG, with the primitives they open."""

    def __init__(
        self,
        connections: list[Connection],
        objects: list[OObject] | None = None,
        *,
        camera: OCameraPrimitive | None = None,
    ):
        """Connect ``objects`` (default: OVirtualRobotComm and Controller), then start them.
        ``camera``: the camera primitive (default: one at Sony's settings FL, MID, MID)."""
        self.camera = camera if camera is not None else OCameraPrimitive()
        self.OPENR = OPENR([self.camera])
        objects = objects if objects is not None else [OVirtualRobotComm(), Controller()]
        self.objects = {obj.stub.object_name: obj for obj in objects}
        self._gates = {str(gate.service.name): gate for obj in objects for gate in (*obj.subject, *obj.observer)}
        for connection in connections:
            subject = self._gate(connection.subject, connection)
            subject.connect(self._gate(connection.observer, connection))
        for obj in objects:
            obj.OPENR = self.OPENR
        for obj in objects:
            obj.DoStart()

    @classmethod
    def from_memory_stick(
        cls,
        memory_stick: str | Path = DEFAULT_MEMORY_STICK,
        objects: list[OObject] | None = None,
        *,
        camera: OCameraPrimitive | None = None,
    ) -> "OpenRSystem":
        """The system a memory stick's CONNECT.CFG wires.

        :raises ConfigError: no CONNECT.CFG, a bad line, or (with the wrapper ``Controller``) no line
            connecting its camera observer.
        """
        path = find_connect_cfg(memory_stick)
        connections = load_connect_cfg(path)
        system = cls(connections, objects, camera=camera)
        controller = system.objects.get("Controller")
        if isinstance(controller, Controller):
            image = next(o for o in controller.observer if str(o.service.name) == IMAGE_SERVICE)
            if not image.is_connected():
                what = "has no connection" if not connections else f"does not connect {IMAGE_SERVICE}"
                raise ConfigError(f"{what}: the camera needs the line '{CAMERA_CONNECTION}'", path)
        return system

    @property
    def robot_comm(self) -> OVirtualRobotComm:
        """The system object ``OVirtualRobotComm``."""
        return self.objects["OVirtualRobotComm"]

    @property
    def controller(self) -> Controller:
        """The wrapper object ``Controller``."""
        return self.objects["Controller"]

    def _gate(self, name: ServiceName, connection: Connection):
        if str(name) in self._gates:
            return self._gates[str(name)]
        known = sorted({gate.service.name.object for gate in self._gates.values()})
        if name.object in known:
            services = sorted(key for key in self._gates if key.startswith(name.object + "."))
            problem = f"{name.object} has no service {cut(name)} (it has {', '.join(services)})"
            if name.object == "Controller":  # the report's wrapper, modelled here for its camera alone
                problem += (
                    "; this model of the wrapper takes the camera's image only: a stick built by "
                    "aibo-sim build-ms runs as itself (aibo-sim run ITS_FOLDER)"
                )
        else:
            problem = f"unknown object {cut(repr(name.object))} (known: {', '.join(known)})"
            problem += "".join(
                f"; object names are case-sensitive: did you mean {candidate!r}?"
                for candidate in known
                if candidate.lower() == name.object.lower()
            )
        raise ConfigError(problem, connection.path, connection.line)
