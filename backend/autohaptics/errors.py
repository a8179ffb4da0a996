"""The one exception family. Messages name the file, the stream, the track or the shape."""


class AutohapticsError(Exception):
    """Base of every error autohaptics raises on purpose (the CLI prints it as one line)."""


class MediaError(AutohapticsError):
    """A media file cannot be used: missing, not media, truncated, no such stream, unreadable codec."""


class ParameterError(AutohapticsError):
    """A parameter, an array shape or a timeline's content is invalid."""


class DeviceError(AutohapticsError):
    """The chair link failed: no such port, handshake refused, device unplugged."""


class CancelledError(AutohapticsError):
    """Long work was cancelled by the user (a job or a CLI run)."""
