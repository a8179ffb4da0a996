"""Serial ports a chair may be on: USB serial devices (pyserial) plus running virtual chairs."""

from __future__ import annotations

from dataclasses import asdict, dataclass

from serial.tools import list_ports as _serial_list_ports

from autohaptics.chair.simulate import virtual_chair_links

# PJRC's USB vendor id; Teensy USB-serial firmware enumerates with it (product 0x0483 for "Serial").
TEENSY_VID = 0x16C0


@dataclass(frozen=True)
class PortInfo:
    device: str
    description: str
    kind: str  # "usb" | "serial" | "virtual"
    vid: int | None = None
    pid: int | None = None
    serial_number: str | None = None
    manufacturer: str | None = None
    likely_chair: bool = False  # a Teensy or a virtual chair

    def to_dict(self) -> dict:
        return asdict(self)


def list_ports() -> list[PortInfo]:
    """Every serial port pyserial sees, then every running virtual chair; likely chairs first."""
    ports = []
    for p in _serial_list_ports.comports():
        ports.append(PortInfo(
            device=p.device, description=p.description or "", kind="usb" if p.vid is not None else "serial",
            vid=p.vid, pid=p.pid, serial_number=p.serial_number, manufacturer=p.manufacturer,
            likely_chair=p.vid == TEENSY_VID))
    for link in virtual_chair_links():
        ports.append(PortInfo(device=str(link), description=f"virtual chair ({link.resolve()})", kind="virtual",
                              likely_chair=True))
    return sorted(ports, key=lambda p: (not p.likely_chair, p.kind != "usb", p.device))
