"""A live feed of a running tree for Groot2's monitor: the request-reply part of BT.CPP v4's
``Groot2Publisher`` protocol (protocol 2), over ZMQ (the optional extra ``groot``: pyzmq).

Groot2 connects to a REP socket on ``port`` (and a PUB socket on ``port + 1``, bound for it; this
feed publishes nothing there: no breakpoints). Every message is multipart. A request's first
part is 6 bytes: protocol (uint8, 2), type (one ASCII byte) and a request id (uint32,
little-endian); a reply's first part repeats them and adds a 16-byte tree id. Answered:

- ``T`` (full tree): the tree's XML, as in ``run.btlog`` (:func:`planner.btlog.groot_tree_xml`);
- ``S`` (status): 3 bytes a node, its uid (uint16) and its status (0 idle, 1 running,
  2 success, 3 failure; idle after a status s is 10 + s, as BT.CPP sends it);
- ``D`` (hooks dump): ``[]``; ``A`` and ``X`` (remove, disable all hooks): nothing to do.

Other requests (blackboard, breakpoints, recording) get BT.CPP's error reply: the parts
``error`` and what went wrong. The sockets bind to the loopback address only.
"""

from __future__ import annotations

import hashlib
import struct
import threading

import py_trees
from py_trees.common import Status

from duet_robot.closing import Closing
from planner.btlog import STATUS_CODES, GrootTree

__all__ = ["PROTOCOL_ID", "GrootPublisher", "GrootUnavailableError", "groot_problem"]

PROTOCOL_ID = 2
#: How long the server waits for a request before it looks whether to stop, ms.
_POLL_MS = 50


class GrootUnavailableError(RuntimeError):
    """pyzmq is not installed, or the port cannot be bound; the message says which."""


def groot_problem(port: int) -> str | None:
    """Why a feed on ``port`` cannot start before trying (no pyzmq, a port out of range), or
    None; a port taken shows only when the feed binds."""
    import importlib.util

    if importlib.util.find_spec("zmq") is None:
        return "--groot: needs pyzmq; install the extra: pip install 'duet-robot[groot]'"
    if not 1 <= port <= 65534:
        return f"--groot: expected a port 1..65534 (it takes PORT and PORT+1), got {port}"
    return None


class GrootPublisher(Closing):
    """Serve a tree's status to Groot2 while it runs (see the module's protocol).

    Parameters
    ----------
    tree : GrootTree
        The tree's XML and uids (the same as the run's ``run.btlog``).
    port : int
        The REP socket's port; the PUB socket takes ``port + 1``.

    Raises
    ------
    GrootUnavailableError
        Without pyzmq, or when a port is taken.
    """

    def __init__(self, tree: GrootTree, port: int) -> None:
        problem = groot_problem(port)
        if problem:
            raise GrootUnavailableError(problem)
        import zmq

        self.tree = tree
        self.port = port
        # The tree id: the same tree gives the same id (nothing random in a run).
        self._tree_id = hashlib.md5(tree.xml.encode("utf-8")).digest()
        self._lock = threading.Lock()
        order = sorted(set(tree.uids.values()) | {u for s in tree.subtree_uids.values() for u in s})
        self._offset = {uid: 3 * i + 2 for i, uid in enumerate(order)}
        self._status = bytearray(b"".join(struct.pack("<HB", uid, 0) for uid in order))
        self._context = zmq.Context()
        self._server = self._context.socket(zmq.REP)
        self._publisher = self._context.socket(zmq.PUB)
        try:
            self._server.bind(f"tcp://127.0.0.1:{port}")
            self._publisher.bind(f"tcp://127.0.0.1:{port + 1}")
        except zmq.ZMQError as err:
            self._close_sockets()
            raise GrootUnavailableError(f"--groot {port}: cannot bind: {err}") from None
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name="groot-publisher", daemon=True)
        self._thread.start()

    # -- status -----------------------------------------------------------------------
    def record(self, node: py_trees.behaviour.Behaviour, before: Status, after: Status) -> None:
        """Note a status change (a :data:`planner.runlog.StatusListener`)."""
        uid = self.tree.uids.get(node.id)
        if uid is None:
            return
        code = STATUS_CODES[after]
        if after == Status.INVALID:
            code = 10 + STATUS_CODES[before]
        with self._lock:
            for each in (uid, *self.tree.subtree_uids.get(node.id, ())):
                self._status[self._offset[each]] = code

    def status_buffer(self) -> bytes:
        """The status part of a reply to ``S``, now."""
        with self._lock:
            return bytes(self._status)

    # -- server -----------------------------------------------------------------------
    def _reply(self, parts: list[bytes]) -> list[bytes]:
        header = parts[0] if parts else b""
        if len(header) != 6:
            return [b"error", b"wrong request header"]
        kind, request_id = chr(header[1]), header[2:6]
        reply = [struct.pack("<BB", PROTOCOL_ID, header[1]) + request_id + self._tree_id]
        if kind == "T":
            return [*reply, self.tree.xml.encode("utf-8")]
        if kind == "S":
            return [*reply, self.status_buffer()]
        if kind == "D":
            return [*reply, b"[]"]
        if kind in ("A", "X"):
            return reply
        return [b"error", f"request '{kind}' is not supported by Duet's feed".encode()]

    def _serve(self) -> None:
        import zmq

        poller = zmq.Poller()
        poller.register(self._server, zmq.POLLIN)
        while not self._stop.is_set():
            try:
                if not dict(poller.poll(_POLL_MS)):
                    continue
                parts = self._server.recv_multipart()
                self._server.send_multipart(self._reply(parts))
            except zmq.ZMQError:
                break

    # -- lifetime ---------------------------------------------------------------------
    def _close_sockets(self) -> None:
        self._server.close(linger=0)
        self._publisher.close(linger=0)
        self._context.term()

    def close(self) -> None:
        """Stop serving and close the sockets (idempotent)."""
        if self._stop.is_set():
            return
        self._stop.set()
        self._thread.join()
        self._close_sockets()
