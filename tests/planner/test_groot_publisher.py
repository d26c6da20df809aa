"""The live feed for Groot2: BT.CPP's Groot2Publisher request-reply protocol over ZMQ, on
loopback, asked as Groot2 asks (a REQ socket, 6-byte request headers)."""

from __future__ import annotations

import random
import struct
from pathlib import Path

import py_trees
import pytest

from planner.btlog import groot_tree_xml
from planner.loader import load_tree_string
from planner.runlog import RunLog
from tests.planner.stub_leaves import FakeClock

zmq = pytest.importorskip("zmq")  # the optional extra duet-robot[groot]

from planner.groot_publisher import GrootPublisher  # noqa: E402

TREE = """
<root BTCPP_format="4" main_tree_to_execute="Main">
  <BehaviorTree ID="Main">
    <Sequence name="seq">
      <StubCounter name="count" ticks="2" count="{n}"/>
      <SubTree ID="Check" name="check_it"/>
    </Sequence>
  </BehaviorTree>
  <BehaviorTree ID="Check">
    <StubCheck name="check" value="true"/>
  </BehaviorTree>
</root>
"""


def ask(port: int, kind: str, request_id: int = 7) -> list[bytes]:
    context = zmq.Context()
    socket = context.socket(zmq.REQ)
    socket.setsockopt(zmq.RCVTIMEO, 5000)
    socket.setsockopt(zmq.LINGER, 0)
    socket.connect(f"tcp://127.0.0.1:{port}")
    try:
        socket.send_multipart([struct.pack("<BBI", 2, ord(kind), request_id)])
        return socket.recv_multipart()
    finally:
        socket.close()
        context.term()


def statuses(buffer: bytes) -> dict[int, int]:
    return {struct.unpack_from("<H", buffer, i)[0]: buffer[i + 2] for i in range(0, len(buffer), 3)}


def test_full_tree_and_status_as_groot2_asks(tmp_path: Path) -> None:
    import tests.planner.stub_leaves  # noqa: F401

    root = load_tree_string(TREE)
    tree = py_trees.trees.BehaviourTree(root)
    groot = groot_tree_xml(root)
    port = random.Random(0).randrange(20000, 40000, 2)
    with GrootPublisher(groot, port) as feed, RunLog(tmp_path / "run.jsonl", FakeClock()) as log:
        log.add_status_listener(feed.record)
        log.attach(tree)
        header, xml = ask(port, "T")
        assert header[:6] == struct.pack("<BBI", 2, ord("T"), 7) and len(header) == 22
        assert xml.decode() == groot.xml
        # before a tick: every node idle, SubTree node included (uids 1..4)
        assert statuses(ask(port, "S")[1]) == {1: 0, 2: 0, 3: 0, 4: 0}
        tree.tick()
        # seq, count running; the SubTree (3) and its check (4) not reached
        assert statuses(ask(port, "S", 8)[1]) == {1: 1, 2: 1, 3: 0, 4: 0}
        tree.tick()
        assert statuses(ask(port, "S")[1]) == {1: 2, 2: 2, 3: 2, 4: 2}
        tree.tick()  # the sequence starts again: check halted from success -> 10 + 2
        assert statuses(ask(port, "S")[1]) == {1: 1, 2: 1, 3: 12, 4: 12}
        assert ask(port, "D")[1] == b"[]"
        assert ask(port, "B") == [b"error", b"request 'B' is not supported by Duet's feed"]
        same_id = ask(port, "S")[0][6:]
        assert same_id == ask(port, "T")[0][6:] and len(same_id) == 16


def test_a_taken_port_is_refused() -> None:
    from planner.groot_publisher import GrootUnavailableError

    root = py_trees.behaviours.Success("ok")
    port = random.Random(1).randrange(20000, 40000, 2)
    with (
        GrootPublisher(groot_tree_xml(root), port),
        pytest.raises(GrootUnavailableError, match=f"--groot {port}: cannot bind"),
    ):
        GrootPublisher(groot_tree_xml(root), port)
    with pytest.raises(GrootUnavailableError, match=r"expected a port 1\.\.65534"):
        GrootPublisher(groot_tree_xml(root), 0)
