"""A small reader of Groot2's ``.btlog`` (BT.CPP FileLogger2) files, for the tests: it parses the
layout from the bytes alone, without :mod:`planner.btlog`, so a test of one checks the other."""

from __future__ import annotations

import struct
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path


@dataclass(frozen=True)
class BtLogFile:
    """What a ``.btlog`` holds: protocol, the tree's XML, first timestamp (us) and the
    transitions as (microseconds since the first timestamp, uid, status code)."""

    protocol: int
    xml: str
    first_us: int
    transitions: list[tuple[int, int, int]]

    def uids(self) -> dict[int, ET.Element]:
        """uid -> element of the tree XML."""
        document = ET.fromstring(self.xml)
        return {int(e.attrib["_uid"]): e for e in document.iter() if "_uid" in e.attrib}


def read_btlog(path: Path) -> BtLogFile:
    data = path.read_bytes()
    magic = b"BTCPP4-FileLogger2"
    assert data[: len(magic)] == magic, data[:32]
    at = len(magic)
    protocol = data[at]
    at += 1
    (size,) = struct.unpack_from("<I", data, at)
    at += 4
    xml = data[at : at + size].decode("utf-8")
    at += size
    (first_us,) = struct.unpack_from("<q", data, at)
    at += 8
    rest = data[at:]
    assert len(rest) % 9 == 0, f"{len(rest)} bytes of transitions: expected 9 a transition"
    transitions = []
    for i in range(0, len(rest), 9):
        delta = int.from_bytes(rest[i : i + 6], "little")
        uid, status = struct.unpack_from("<HB", rest, i + 6)
        transitions.append((delta, uid, status))
    return BtLogFile(protocol, xml, first_us, transitions)
