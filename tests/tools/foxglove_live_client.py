"""Connects to a Foxglove WebSocket server (subprotocol foxglove.sdk.v1) with the PyPI package
`websockets`, subscribes to every channel it advertises, decodes each message with the
protobuf schema the server advertised (PyPI `protobuf`), and when the server closes the
connection prints what it received as one JSON object:

    {"channels": {TOPIC: {"schema_name", "encoding", "schema_encoding", "count"}},
     "scans": [{"ranges", "start_angle", "end_angle", "frame_id", "stamp"}],
     "poses": {TOPIC: [[x, y, qz, qw]]}, "tf": [[parent, child]], "tf_static": [[parent, child]],
     "maps": [{"columns", "rows", "cell_size", "fields", "frame_id"}],
     "markers": {ENTITY_ID: COUNT}, "server_name": NAME, "closed": HOW}

Usage: python3 foxglove_live_client.py ws://HOST:PORT [TIMEOUT_S [WATCH_S]]

It retries while nothing listens at the address yet, and gives up after TIMEOUT_S (120 s).
With WATCH_S it stops on its own WATCH_S seconds after connecting ("closed": "watched").

Written for goalseek's tests from the protocol's public description; it shares no code with
the server.
"""
import asyncio
import base64
import json
import math
import struct
import sys

from google.protobuf import descriptor_pb2, descriptor_pool, message_factory
from websockets.asyncio.client import connect
from websockets.exceptions import ConnectionClosed
from websockets.typing import Subprotocol


def message_class(schema_name: str, schema_b64: str):
    """The protobuf class of `schema_name` from a base64 FileDescriptorSet."""
    files = descriptor_pb2.FileDescriptorSet.FromString(base64.b64decode(schema_b64)).file
    pool = descriptor_pool.DescriptorPool()
    pending = list(files)
    added = set()
    while pending:
        ready = [f for f in pending if all(d in added for d in f.dependency)]
        if not ready:
            raise ValueError(f"{schema_name}: unresolved dependencies")
        for f in ready:
            pool.Add(f)
            added.add(f.name)
            pending.remove(f)
    return message_factory.GetMessageClass(pool.FindMessageTypeByName(schema_name))


def finite(x: float):
    """A number for JSON: inf and nan as strings."""
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return x


async def watch(url: str, watch_s: float | None) -> dict:
    out = {
        "channels": {},
        "scans": [],
        "poses": {},
        "tf": [],
        "tf_static": [],
        "maps": [],
        "markers": {},
        "server_name": None,
        "closed": None,
    }
    by_sub = {}
    async with connect(
        url, subprotocols=[Subprotocol("foxglove.sdk.v1")], max_size=None
    ) as ws:
        assert ws.subprotocol == "foxglove.sdk.v1", ws.subprotocol
        try:
            await asyncio.wait_for(receive(ws, out, by_sub), watch_s)
            out["closed"] = "normal"
        except asyncio.TimeoutError:
            out["closed"] = "watched"
        except ConnectionClosed as e:
            out["closed"] = f"closed: {e}"
    return out


async def receive(ws, out: dict, by_sub: dict) -> None:
    """Subscribes to every advertised channel and records what arrives, until the end."""
    next_sub = 1
    async for frame in ws:
        if isinstance(frame, str):
            msg = json.loads(frame)
            if msg.get("op") == "serverInfo":
                out["server_name"] = msg.get("name")
            elif msg.get("op") == "advertise":
                subs = []
                for ch in msg["channels"]:
                    topic = ch["topic"]
                    out["channels"][topic] = {
                        "schema_name": ch.get("schemaName"),
                        "encoding": ch.get("encoding"),
                        "schema_encoding": ch.get("schemaEncoding"),
                        "count": 0,
                    }
                    cls = None
                    if ch.get("encoding") == "protobuf":
                        cls = message_class(ch["schemaName"], ch["schema"])
                    by_sub[next_sub] = (topic, cls)
                    subs.append({"id": next_sub, "channelId": ch["id"]})
                    next_sub += 1
                await ws.send(json.dumps({"op": "subscribe", "subscriptions": subs}))
            continue
        if not frame or frame[0] != 0x01:
            continue
        sub_id, _log_time = struct.unpack_from("<IQ", frame, 1)
        topic, cls = by_sub[sub_id]
        out["channels"][topic]["count"] += 1
        if cls is None:
            continue
        m = cls.FromString(frame[13:])
        name = cls.DESCRIPTOR.full_name
        if name == "foxglove.LaserScan":
            out["scans"].append(
                {
                    "ranges": len(m.ranges),
                    "hits": sum(1 for r in m.ranges if math.isfinite(r)),
                    "start_angle": m.start_angle,
                    "end_angle": m.end_angle,
                    "frame_id": m.frame_id,
                    "stamp": m.timestamp.seconds + m.timestamp.nanos * 1e-9,
                    "max": finite(max(m.ranges)) if m.ranges else None,
                }
            )
        elif name == "foxglove.PoseInFrame":
            p = m.pose
            out["poses"].setdefault(topic, []).append(
                [p.position.x, p.position.y, p.orientation.z, p.orientation.w, m.frame_id]
            )
        elif name == "foxglove.FrameTransforms":
            key = "tf_static" if topic == "/tf_static" else "tf"
            for t in m.transforms:
                out[key].append([t.parent_frame_id, t.child_frame_id])
        elif name == "foxglove.Grid":
            rows = len(m.data) // m.row_stride if m.row_stride else 0
            out["maps"].append(
                {
                    "columns": m.column_count,
                    "rows": rows,
                    "cell_size": [m.cell_size.x, m.cell_size.y],
                    "fields": [[f.name, f.offset, f.type] for f in m.fields],
                    "frame_id": m.frame_id,
                    "values": sorted(set(struct.unpack(f"{len(m.data)}b", m.data))),
                }
            )
        elif name == "foxglove.SceneUpdate":
            for e in m.entities:
                n = len(e.spheres) + len(e.cubes) + len(e.cylinders)
                out["markers"][e.id] = n


async def watch_when_up(url: str, watch_s: float | None) -> dict:
    """`watch`, retrying while the server is not listening yet."""
    while True:
        try:
            return await watch(url, watch_s)
        except OSError:
            await asyncio.sleep(0.1)


def main() -> None:
    url = sys.argv[1]
    timeout_s = float(sys.argv[2]) if len(sys.argv) > 2 else 120.0
    watch_s = float(sys.argv[3]) if len(sys.argv) > 3 else None
    out = asyncio.run(asyncio.wait_for(watch_when_up(url, watch_s), timeout_s))
    json.dump(out, sys.stdout)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
