"""The chair: wire protocol, serial link, live playback and the virtual chair.

What the web service uses::

    from autohaptics.chair import ChairLink, ChairPlayer, Comfort, list_ports, push

    ports = list_ports()                       # [PortInfo]; Teensys and virtual chairs first
    link = ChairLink(port); link.connect()     # HELLO -> capabilities; reconnects by itself
    player = ChairPlayer(link, timeline, comfort=Comfort(intensity=0.8, mute={"heat"}),
                         latency_offset_ms=40)
    player.play(12.3); player.seek(40.0); player.pause(); player.stop()
    player.status().to_dict()                  # position, frames sent, link and chair diagnostics
    player.close(); link.close()

The protocol is specified in firmware/PROTOCOL.md; :mod:`autohaptics.chair.protocol` mirrors it.
"""

from autohaptics.chair.comfort import MUTABLE_ZONES, Comfort, DeviceProfile, compose_frame
from autohaptics.chair.link import ChairLink, LinkStatus
from autohaptics.chair.player import ChairPlayer, PlayerStatus, follow_range, push, start_range
from autohaptics.chair.ports import PortInfo, list_ports
from autohaptics.chair.protocol import ChairStatus, Frame, Hello, ProtocolError
from autohaptics.chair.simulate import VirtualChair, build_simulator

__all__ = [
    "ChairLink", "LinkStatus", "ChairPlayer", "PlayerStatus", "push", "start_range", "follow_range", "Comfort", "DeviceProfile", "MUTABLE_ZONES",
    "compose_frame", "PortInfo", "list_ports", "ChairStatus", "Frame", "Hello", "ProtocolError", "VirtualChair",
    "build_simulator",
]
