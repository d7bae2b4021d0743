"""OPEN-R inter-object communication: subjects, observers, notify events, objects.

Semantics (report section 2.1.2, spec section 1): a subject sends its data only to observers
that asserted ready; a delivery uses that readiness up, so the observer's Notify handler
calls ``AssertReady`` for the next one. A connection keeps the newest undelivered data (the
OPEN-R default buffer of one) and hands it over as soon as the observer is ready again;
data it replaces is counted as dropped (``OSubject.dropped``). Subjects' ``Ready()``
members are not called: no object here needs them.
"""

from pathlib import Path

from .config import Service, StubConfig, load_stub_cfg
from .errors import ConfigError, NotConnectedError

DATA_DIR = Path(__file__).parent / "data"


class ONotifyEvent:
    """What an observer's Notify handler receives."""

    def __init__(self, data: list, obs_index: int, sender: "OSubject"):
        self._data = data
        self._obs_index = obs_index
        self._sender = sender

    def Data(self, index: int = 0):
        """The ``index``-th data item delivered."""
        return self._data[index]

    def NumOfData(self) -> int:
        """Number of data items delivered."""
        return len(self._data)

    def ObsIndex(self) -> int:
        """Index of the receiving observer among its object's observers."""
        return self._obs_index

    def SenderID(self) -> "OSubject":
        """The subject that sent the data."""
        return self._sender


class _Link:
    """One connection: the observer's readiness and the newest undelivered data."""

    def __init__(self, subject: "OSubject", observer: "OObserver"):
        self.subject = subject
        self.observer = observer
        self.ready = False
        self.pending = None
        self.dropped = 0

    def offer(self, data) -> None:
        if self.pending is not None:
            self.dropped += 1
        self.pending = data
        self._deliver()

    def set_ready(self, ready: bool) -> None:
        self.ready = ready
        self._deliver()

    def _deliver(self) -> None:
        if self.ready and self.pending is not None:
            data, self.pending, self.ready = self.pending, None, False
            self.observer.receive(ONotifyEvent([data], self.observer.index, self.subject))


class OSubject:
    """A subject service: sends its data to the connected observers that are ready."""

    def __init__(self, service: Service):
        self.service = service
        self._links: list[_Link] = []
        self._data = None

    def connect(self, observer: "OObserver") -> None:
        """Connect ``observer`` (not ready until it asserts ready)."""
        link = _Link(self, observer)
        self._links.append(link)
        observer.links.append(link)

    def SetData(self, data) -> None:
        """The data the next ``NotifyObservers`` sends."""
        self._data = data

    def NotifyObservers(self) -> None:
        """Offer the data to each connection: delivered at once to a ready observer, else kept."""
        for link in self._links:
            link.offer(self._data)

    @property
    def dropped(self) -> dict[str, int]:
        """Data each connected observer missed, by observer service name."""
        return {str(link.observer.service.name): link.dropped for link in self._links}


class OObserver:
    """An observer service: ``handler`` (its object's Notify method, or None) receives the data."""

    def __init__(self, service: Service, index: int, handler):
        self.service = service
        self.index = index
        self.handler = handler
        self.links: list[_Link] = []

    def AssertReady(self, sender: OSubject | None = None) -> None:
        """Ready for the next data from ``sender``, or from every connected subject."""
        for link in self._links_to(sender):
            link.set_ready(True)

    def DeassertReady(self, sender: OSubject | None = None) -> None:
        """Not ready for data from ``sender``, or from every connected subject."""
        for link in self._links_to(sender):
            link.set_ready(False)

    def is_connected(self) -> bool:
        """Whether any subject is connected to it."""
        return bool(self.links)

    def receive(self, event: ONotifyEvent) -> None:
        """Pass ``event`` to the handler, if any."""
        if self.handler is not None:
            self.handler(event)

    def _links_to(self, sender: OSubject | None) -> list[_Link]:
        links = [link for link in self.links if sender is None or link.subject is sender]
        if sender is not None and not links:
            raise NotConnectedError(f"{self.service.name} is not connected to {sender.service.name}")
        return links


class OObject:
    """An OPEN-R object: ``subject`` and ``observer`` follow its stub.cfg, in listed order."""

    def __init__(self, stub: StubConfig):
        self.stub = stub
        self.subject = [OSubject(service) for service in stub.of_kind("S")]
        self.observer = [OObserver(service, i, self._handler(service)) for i, service in enumerate(stub.of_kind("O"))]

    def DoStart(self) -> None:
        """Called once the system has made every connection."""

    def _handler(self, service: Service):
        if service.notify_method is None:
            return None
        handler = getattr(self, service.notify_method, None)
        if not callable(handler):
            raise ConfigError(
                f"{type(self).__name__} has no method {service.notify_method}()", self.stub.path, service.line
            )
        return handler


class OVirtualRobotComm(OObject):
    """The system object's camera side: publishes ``FbkImageSensor.OFbkImageVectorData.S``."""

    def __init__(self):
        super().__init__(load_stub_cfg(DATA_DIR / "OVirtualRobotComm" / "stub.cfg"))

    @property
    def image_subject(self) -> OSubject:
        """The camera image subject, ``FbkImageSensor.OFbkImageVectorData.S``."""
        return self.subject[0]

    def publish_image(self, message) -> None:
        """Send an ``OFbkImageVectorData`` to every connected, ready observer."""
        self.image_subject.SetData(message)
        self.image_subject.NotifyObservers()
