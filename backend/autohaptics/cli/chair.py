"""``autohaptics chair ports|simulate|push|stop|status``: the chair from the command line."""

from __future__ import annotations

import argparse
import json
import signal
import sys
import threading

from autohaptics.cli.main import command_group
from autohaptics.errors import DeviceError
from autohaptics.progress import ProgressBar

COMMAND = "chair"
HELP = "talk to the haptic chair (or a virtual one)"


def register(sub) -> None:
    chair_sub = command_group(sub, COMMAND, HELP, "List ports, run a virtual chair, push a timeline, stop, read status.",
                              dest="chair_command", metavar="ACTION")

    q = chair_sub.add_parser("ports", help="list serial ports and running virtual chairs")
    q.add_argument("--json", action="store_true", help="print JSON")
    q.set_defaults(func=_ports)

    q = chair_sub.add_parser("simulate", help="run a virtual chair on a pseudo-terminal until Ctrl-C")
    q.add_argument("--log", metavar="FILE", help="JSON-lines log of applied frames and state changes")
    q.add_argument("--name", default="chair0", help="virtual chair name (its device link; default chair0)")
    q.add_argument("--link", metavar="PATH", help="device link path (default: in the runtime directory)")
    q.add_argument("--build-dir", metavar="DIR", help="where to build the simulator (default ~/.cache/autohaptics)")
    q.set_defaults(func=_simulate)

    q = chair_sub.add_parser("push", help="play a timeline (or a range of it) on the chair at 10 Hz")
    q.add_argument("timeline", metavar="TIMELINE.json")
    _port_arg(q)
    q.add_argument("--start", type=float, default=0.0, metavar="S", help="start position, seconds")
    q.add_argument("--end", type=float, default=None, metavar="S", help="end position, seconds (default: the end)")
    q.add_argument("--intensity", type=float, default=1.0, help="comfort: global intensity 0..1")
    q.add_argument("--mute", action="append", default=[], metavar="ZONE",
                   help="comfort: mute a zone (back, armrests, seat, heat, fans); repeatable")
    q.set_defaults(func=_push)

    q = chair_sub.add_parser("stop", help="turn every output off now")
    _port_arg(q)
    q.set_defaults(func=_stop)

    q = chair_sub.add_parser("status", help="handshake and print the chair's capabilities and counters")
    _port_arg(q)
    q.add_argument("--json", action="store_true", help="print JSON")
    q.set_defaults(func=_status)


def _port_arg(q: argparse.ArgumentParser) -> None:
    q.add_argument("--port", required=True, metavar="P", help="serial device (see `autohaptics chair ports`)")


def _ports(args) -> int:
    from autohaptics.chair.ports import list_ports

    ports = list_ports()
    if args.json:
        print(json.dumps([p.to_dict() for p in ports], indent=2))
        return 0
    if not ports:
        print("no serial ports found (start a virtual chair with `autohaptics chair simulate`)")
    for p in ports:
        ident = f" {p.vid:04x}:{p.pid:04x}" if p.vid is not None and p.pid is not None else ""
        mark = "*" if p.likely_chair else " "
        print(f"{mark} {p.device:<40} {p.kind:<8}{ident} {p.description}")
    return 0


def _simulate(args) -> int:
    from autohaptics.chair.simulate import VirtualChair

    chair = VirtualChair(link_path=args.link, log_path=args.log, name=args.name, build_dir=args.build_dir)
    stop = threading.Event()
    previous = signal.signal(signal.SIGTERM, lambda *a: stop.set())
    try:
        with chair:
            print(chair.device, flush=True)
            print(f"virtual chair running on {chair.pty} (pid {chair.pid}); link {chair.device}"
                  + (f"; log {chair.log_path}" if chair.log_path else "") + "; Ctrl-C to stop",
                  file=sys.stderr, flush=True)
            try:
                while chair.alive and not stop.wait(0.2):
                    pass
            except KeyboardInterrupt:
                pass
    finally:
        signal.signal(signal.SIGTERM, previous)
    return 0


def _push(args) -> int:
    from autohaptics.chair.comfort import Comfort
    from autohaptics.chair.link import ChairLink
    from autohaptics.chair.player import push
    from autohaptics.timeline import Timeline

    timeline = Timeline.load(args.timeline)
    comfort = Comfort(intensity=args.intensity, mute=frozenset(args.mute))
    with ChairLink(args.port) as link, ProgressBar("push") as bar:
        status = push(link, timeline, start_s=args.start, end_s=args.end, comfort=comfort, progress=bar)
    print(f"pushed {status.frames_sent} frames to {args.port} (last tick {status.tick}, "
          f"{status.frames_dropped} dropped while disconnected, {status.ticks_skipped} skipped)")
    return 0


def _stop(args) -> int:
    from autohaptics.chair.link import ChairLink

    with ChairLink(args.port, stop_on_close=False) as link:
        if not link.send_stop():
            raise DeviceError(f"could not send STOP to {args.port}: the chair went away")
        chair = link.request_status(1.0)
    state = "safe" if chair is not None and chair.safe else "unknown"
    print(f"STOP sent to {args.port}; chair state: {state}")
    return 0


def _status(args) -> int:
    from autohaptics.chair.link import ChairLink

    with ChairLink(args.port, stop_on_close=False) as link:
        link.request_status(1.0)
        status = link.status()
    if args.json:
        print(json.dumps(status.to_dict(), indent=2))
        return 0
    caps, chair = status.capabilities or {}, status.chair
    print(f"port {status.port}: {caps.get('name')} firmware {caps.get('firmware_version')}, "
          f"protocol {caps.get('protocol_version')}, {caps.get('n_actuators')} actuators, "
          f"fans {caps.get('fan_rows')}x{caps.get('fan_cols')}, temperature {caps.get('temp_min_c')}.."
          f"{caps.get('temp_max_c')} C (neutral {caps.get('temp_neutral_c')} C, {caps.get('temp_rate_c_per_s')} C/s), "
          f"watchdog {caps.get('watchdog_ms')} ms")
    if chair is None:
        print("no STATUS received")
        return 0
    print(f"state: {'safe (' + chair['safe_reason'] + ')' if chair['safe'] else 'running'}, uptime "
          f"{chair['uptime_ms'] / 1000:.1f} s, last tick {chair['last_tick'] if chair['has_tick'] else '-'}, "
          f"temperature {chair['temp_setpoint_c']:.2f} C -> {chair['temp_target_c']:.2f} C")
    keys = ("frames_ok", "packets_ok", "crc_errors", "length_errors", "overflows", "version_errors", "type_errors",
            "stale_frames", "seq_gaps", "late_frames", "watchdog_trips", "tx_dropped")
    print("counters: " + ", ".join(f"{k} {chair[k]}" for k in keys))
    return 0
