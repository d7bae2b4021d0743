"""The exceptions of openr_bridge: every failure it reports is an OpenRError."""


class OpenRError(Exception):
    """Base class of every error raised by openr_bridge."""


class MessageFormatError(OpenRError):
    """Bytes that do not form a valid OFbkImageVectorData message."""


class ImageAccessError(OpenRError):
    """A layer, band or pixel that the message does not have."""


class FrameError(OpenRError):
    """An input array of the wrong shape or dtype."""


class CdtError(OpenRError):
    """A colour detection table the ERS-7 cannot use."""


class ConfigError(OpenRError):
    """A malformed or inconsistent stub.cfg or CONNECT.CFG; names the file and line."""

    def __init__(self, message: str, path, line: int | None = None):
        self.path = str(path)
        self.line = line
        where = self.path if line is None else f"{self.path}:{line}"
        super().__init__(f"{where}: {message}")


class NotRegularFile(OpenRError):
    """A FIFO, folder, device or socket where a regular file was to be read."""


class NotConnectedError(OpenRError):
    """An observer that no CONNECT.CFG line connects to a subject, or a wrapper used outside an
    OpenRSystem (no OPENR to open primitives with)."""


class NoImageError(OpenRError):
    """A camera function called before the first image arrived."""


class PrimitiveError(OpenRError):
    """An OPEN-R primitive call (``OPENR.OpenPrimitive``, ``ControlPrimitive``, ...) that did not
    return ``oSUCCESS``; ``status`` is the OStatus it returned."""

    def __init__(self, message: str, status: int):
        self.status = status
        super().__init__(message)
