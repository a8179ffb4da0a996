"""The serial link to a chair (pyserial): handshake, frames out, STATUS in, automatic reconnect.

Usage (what the web service calls)::

    link = ChairLink("/dev/ttyACM0")
    caps = link.connect()            # opens the port, HELLO -> capabilities, starts the I/O thread
    link.send_frame(frame)           # False while disconnected (the frame is dropped and counted)
    link.send_stop()                 # every output off now
    link.status()                    # LinkStatus snapshot, .to_dict() for JSON
    link.close()                     # sends STOP, stops the thread, closes the port

One I/O thread per link reads the port, keeps the chair's STATUS fresh (a STATUS request every
``status_interval_s``) and owns reconnection: when the port errors or vanishes (unplug, virtual
chair killed) or the chair stays silent for ``silence_timeout_s``, it reopens the same path with
exponential backoff and repeats the handshake; ``on("connected", fn)`` listeners then resume.
Frames are written by the caller's thread under a lock; the link numbers them (``seq``).
"""

from __future__ import annotations

import collections
import dataclasses
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import serial

from autohaptics.chair.comfort import DeviceProfile
from autohaptics.chair.protocol import (
    FAN_COLS,
    FAN_ROWS,
    N_MOTORS,
    PROTOCOL_VERSION,
    ChairStatus,
    Frame,
    Hello,
    HelloRequest,
    Parsed,
    Parser,
    Status,
    StatusRequest,
    Stop,
    encode,
)
from autohaptics.errors import DeviceError, ParameterError

EVENTS = ("connected", "disconnected", "status", "sent")


@dataclass(frozen=True)
class LinkStatus:
    """A snapshot of the link. ``chair`` is the chair's last STATUS (its own counters)."""

    port: str
    state: str  # "idle" | "connected" | "reconnecting" | "disconnected" | "closed"
    connected: bool
    capabilities: dict | None
    frames_sent: int
    frames_dropped: int
    last_tick_sent: int | None
    last_seq: int
    reconnects: int
    last_error: str | None
    errors: tuple[str, ...]
    chair: dict | None
    chair_status_age_s: float | None
    rx: dict  # the host's parser counters for the chair -> host direction

    def to_dict(self) -> dict:
        d = dataclasses.asdict(self)
        d["errors"] = list(self.errors)
        return d


class ChairLink:
    """A chair on a serial port. Thread-safe; see the module docstring."""

    def __init__(self, port: str, *, baudrate: int = 115200, reconnect: bool = True,
                 handshake_timeout_s: float = 1.0, backoff_s: tuple[float, float] = (0.05, 1.0),
                 status_interval_s: float = 0.5, silence_timeout_s: float = 2.0, write_timeout_s: float = 0.5,
                 stop_on_close: bool = True):
        if not port:
            raise ParameterError("a chair port is needed (e.g. /dev/ttyACM0; see `autohaptics chair ports`)")
        if not 0 < backoff_s[0] <= backoff_s[1]:
            raise ParameterError(f"backoff_s must be (first, max) with 0 < first <= max, got {backoff_s}")
        self.port = str(port)
        self.baudrate = int(baudrate)
        self.reconnect = bool(reconnect)
        self.handshake_timeout_s = float(handshake_timeout_s)
        self.backoff_s = (float(backoff_s[0]), float(backoff_s[1]))
        self.status_interval_s = float(status_interval_s)
        self.silence_timeout_s = float(silence_timeout_s)
        self.write_timeout_s = float(write_timeout_s)
        self.stop_on_close = bool(stop_on_close)

        self._lock = threading.RLock()
        self._cv = threading.Condition(self._lock)
        self._ser: serial.Serial | None = None  # the writable port; None while disconnected
        self._thread: threading.Thread | None = None
        self._closing = threading.Event()
        self._state = "idle"
        self._hello: Hello | None = None
        self._parser = Parser()
        self._seq = 0
        self._frames_sent = 0
        self._frames_dropped = 0
        self._last_tick: int | None = None
        self._reconnects = 0
        self._errors: collections.deque[str] = collections.deque(maxlen=20)
        self._last_error: str | None = None
        self._chair: ChairStatus | None = None
        self._chair_t: float | None = None
        self._status_count = 0
        self._listeners: dict[str, list[Callable[..., Any]]] = {e: [] for e in EVENTS}

    # ------------------------------------------------------------------ public
    def connect(self) -> Hello:
        """Open the port and handshake (HELLO -> capabilities); start the I/O thread.

        Raises DeviceError naming the port when it cannot be opened or no chair answers.
        """
        with self._lock:
            if self._thread is not None:
                if self._hello is None:
                    raise DeviceError(f"chair link {self.port} is closed")
                return self._hello
        ser, hello = self._open()
        with self._lock:
            self._ser, self._hello, self._state = ser, hello, "connected"
            self._thread = threading.Thread(target=self._run, args=(ser,), name=f"chair-link {self.port}",
                                            daemon=True)
            self._thread.start()
            self._cv.notify_all()
        self._emit("connected", hello)
        return hello

    def close(self) -> None:
        """Send STOP (when connected and ``stop_on_close``), stop the I/O thread, close the port."""
        if self.stop_on_close and self.connected:
            self.send_stop()
        self._closing.set()
        with self._lock:
            ser = self._ser
            self._ser = None
            self._state = "closed"
            self._cv.notify_all()
        if ser is not None:
            _cancel(ser)
        thread = self._thread
        if thread is not None and thread is not threading.current_thread():
            thread.join(5.0)
        if thread is None and ser is not None:
            ser.close()

    def __enter__(self) -> "ChairLink":
        self.connect()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    @property
    def connected(self) -> bool:
        return self._ser is not None

    @property
    def capabilities(self) -> Hello | None:
        return self._hello

    @property
    def profile(self) -> DeviceProfile:
        """The device's safe temperature range (from HELLO; layout defaults before the first one)."""
        hello = self._hello
        return DeviceProfile.from_hello(hello) if hello is not None else DeviceProfile()

    def on(self, event: str, fn: Callable[..., Any]) -> Callable[[], None]:
        """Subscribe to "connected" (hello), "disconnected" (reason), "status" (ChairStatus) or
        "sent" (tick, seq, t_ns); returns the unsubscribe function. Listeners run on the link's
        threads and must return quickly."""
        if event not in self._listeners:
            raise ParameterError(f"unknown link event {event!r}; events are {', '.join(EVENTS)}")
        with self._lock:
            self._listeners[event].append(fn)

        def unsubscribe() -> None:
            with self._lock:
                if fn in self._listeners[event]:
                    self._listeners[event].remove(fn)
        return unsubscribe

    def wait_connected(self, timeout_s: float) -> bool:
        with self._cv:
            return self._cv.wait_for(lambda: self._ser is not None or self._closing.is_set(), timeout_s) \
                and self._ser is not None

    def send_frame(self, frame: Frame) -> bool:
        """Number and write one FRAME. False when disconnected or the write failed (dropped, counted)."""
        with self._lock:
            ser = self._ser
            if ser is None:
                self._frames_dropped += 1
                return False
            seq = (self._seq + 1) & 0xFFFF
            wire = encode(dataclasses.replace(frame, seq=seq))
            t_ns = time.monotonic_ns()  # the send time: CLOCK_MONOTONIC as the frame goes to the OS
            try:
                ser.write(wire)
                failure = None
            except (serial.SerialException, OSError) as exc:
                self._frames_dropped += 1
                failure = f"write failed: {exc}"
            else:
                self._seq = seq
                self._frames_sent += 1
                self._last_tick = frame.tick
        if failure is not None:
            self._lose(ser, failure)  # outside the lock: "disconnected" listeners may take their own locks
            return False
        self._emit("sent", frame.tick, seq, t_ns)
        return True

    def send_stop(self) -> bool:
        """STOP: every output off now. False when disconnected."""
        return self._write_current(encode(Stop()))

    def request_status(self, timeout_s: float = 1.0) -> ChairStatus | None:
        """Ask for a STATUS and wait for it; None when disconnected or no answer in time."""
        with self._lock:
            count = self._status_count
        if not self._write_current(encode(StatusRequest())):
            return None
        with self._cv:
            if self._cv.wait_for(lambda: self._status_count > count, timeout_s):
                return self._chair
        return None

    def status(self) -> LinkStatus:
        with self._lock:
            now = time.monotonic()
            return LinkStatus(
                port=self.port, state=self._state, connected=self._ser is not None,
                capabilities=self._hello.to_dict() if self._hello else None,
                frames_sent=self._frames_sent, frames_dropped=self._frames_dropped,
                last_tick_sent=self._last_tick, last_seq=self._seq, reconnects=self._reconnects,
                last_error=self._last_error, errors=tuple(self._errors),
                chair=self._chair.to_dict() if self._chair else None,
                chair_status_age_s=(now - self._chair_t) if self._chair_t is not None else None,
                rx=dataclasses.asdict(self._parser.counters))

    # ----------------------------------------------------------------- private
    def _open(self) -> tuple[serial.Serial, Hello]:
        try:
            ser = serial.Serial(self.port, self.baudrate, timeout=0.02, write_timeout=self.write_timeout_s,
                                exclusive=True)
        except (serial.SerialException, OSError, ValueError) as exc:
            raise DeviceError(f"cannot open chair port {self.port}: {exc}") from None
        try:
            ser.reset_input_buffer()
            parser = Parser()
            deadline = time.monotonic() + self.handshake_timeout_s
            next_request = 0.0
            while time.monotonic() < deadline:
                if time.monotonic() >= next_request:
                    ser.write(b"\x00" + encode(HelloRequest()))  # the leading delimiter ends any stale partial frame
                    next_request = time.monotonic() + 0.25
                for item in parser.feed(ser.read(max(1, ser.in_waiting))):
                    if item.status == Status.OK and isinstance(item.message, Hello):
                        _check_capabilities(self.port, item.message)
                        return ser, item.message
            raise DeviceError(f"no HELLO from {self.port} within {self.handshake_timeout_s:g} s: is an autohaptics "
                              "chair (firmware flashed, protocol version 1) on this port?")
        except (serial.SerialException, OSError) as exc:
            ser.close()
            raise DeviceError(f"chair port {self.port} failed during the handshake: {exc}") from None
        except DeviceError:
            ser.close()
            raise

    def _run(self, ser: serial.Serial | None) -> None:
        backoff = self.backoff_s[0]
        last_rx = last_request = time.monotonic()
        while not self._closing.is_set():
            if ser is not None and ser is not self._ser:  # a writer found it dead, or close()
                ser.close()
                ser = None
            if ser is None:
                if not self.reconnect:
                    with self._lock:
                        if self._state != "closed":
                            self._state = "disconnected"
                    break
                try:
                    ser, hello = self._open()
                except DeviceError as exc:
                    self._note_error(str(exc), repeat=False)
                    self._closing.wait(backoff)
                    backoff = min(backoff * 2.0, self.backoff_s[1])
                    continue
                with self._lock:
                    if self._closing.is_set():
                        break
                    self._ser, self._hello, self._state = ser, hello, "connected"
                    self._reconnects += 1
                    self._parser = Parser(counters=self._parser.counters)  # fresh stream, same totals
                    self._chair = self._chair_t = None  # the old session's STATUS no longer describes this chair
                    self._cv.notify_all()
                backoff = self.backoff_s[0]
                last_rx = last_request = time.monotonic()
                self._emit("connected", hello)
                continue
            try:
                data = ser.read(max(1, ser.in_waiting))
            except (serial.SerialException, OSError, TypeError) as exc:
                self._lose(ser, f"read failed: {exc}")
                continue
            now = time.monotonic()
            if data:
                last_rx = now
                for item in self._parser.feed(data):
                    self._on_parsed(item, now)
            if now - last_request >= self.status_interval_s:
                last_request = now
                self._write_current(encode(StatusRequest()))
            if now - last_rx > self.silence_timeout_s:
                self._lose(ser, f"no reply from the chair for {self.silence_timeout_s:g} s")
        if ser is not None:
            ser.close()

    def _on_parsed(self, item: Parsed, now: float) -> None:
        msg = item.message
        if isinstance(msg, ChairStatus):
            with self._lock:
                self._chair, self._chair_t = msg, now
                self._status_count += 1
                self._cv.notify_all()
            self._emit("status", msg)
        elif isinstance(msg, Hello):
            with self._lock:
                self._hello = msg

    def _write_current(self, data: bytes) -> bool:
        with self._lock:
            ser = self._ser
            if ser is None:
                return False
            try:
                ser.write(data)
                return True
            except (serial.SerialException, OSError) as exc:
                failure = f"write failed: {exc}"
        self._lose(ser, failure)
        return False

    def _lose(self, ser: serial.Serial, reason: str) -> None:
        """Mark ``ser`` dead; the I/O thread closes it and reconnects."""
        with self._lock:
            if self._ser is not ser:
                return
            self._ser = None
            if self._state != "closed":
                self._state = "reconnecting" if self.reconnect else "disconnected"
            self._note_error(f"{self.port}: {reason}")
            self._cv.notify_all()
        if threading.current_thread() is not self._thread:
            _cancel(ser)
        self._emit("disconnected", reason)

    def _note_error(self, message: str, *, repeat: bool = True) -> None:
        with self._lock:
            if not repeat and message == self._last_error:
                return
            self._last_error = message
            self._errors.append(f"{time.strftime('%H:%M:%S')} {message}")

    def _emit(self, event: str, *args: Any) -> None:
        with self._lock:
            listeners = list(self._listeners[event])
        for fn in listeners:
            try:
                fn(*args)
            except Exception as exc:  # a faulty listener must not take the link down
                self._note_error(f"{event} listener {getattr(fn, '__qualname__', fn)!s} failed: "
                                 f"{type(exc).__name__}: {exc}")


def _check_capabilities(port: str, hello: Hello) -> None:
    if hello.protocol_version != PROTOCOL_VERSION:
        raise DeviceError(f"chair on {port} speaks protocol version {hello.protocol_version}, "
                          f"this build speaks {PROTOCOL_VERSION}")
    if (hello.n_actuators, hello.fan_rows, hello.fan_cols) != (N_MOTORS, FAN_ROWS, FAN_COLS):
        raise DeviceError(f"chair on {port} has {hello.n_actuators} actuators and a {hello.fan_rows}x{hello.fan_cols} "
                          f"fan grid; this build drives {N_MOTORS} and {FAN_ROWS}x{FAN_COLS}")
    if not hello.temp_min_cc <= hello.temp_neutral_cc <= hello.temp_max_cc:
        raise DeviceError(f"chair on {port} reports an invalid temperature range "
                          f"{hello.temp_min_c}..{hello.temp_max_c} C (neutral {hello.temp_neutral_c} C)")


def _cancel(ser: serial.Serial) -> None:
    """Wake a thread blocked in ser.read() without closing the port under it."""
    cancel = getattr(ser, "cancel_read", None)
    if cancel is not None:
        try:
            cancel()
        except (OSError, serial.SerialException):
            pass
