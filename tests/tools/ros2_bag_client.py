#!/usr/bin/env python3
"""Opens a `robot-app ... --record FILE --profile ros2` recording with two readers nobody here
wrote, `rosbags` (AnyReader) and `mcap-ros2-support`, decodes every message and prints one
JSON object: per-topic types and counts, the first and last scans, every pose and transform,
the map, and the MCAP metadata names (read with the `mcap` package).

Usage: ros2_bag_client.py FILE.mcap
"""

import json
import math
import sys
from pathlib import Path


def num(x):
    """A float for JSON: non-finite values as the strings 'inf', '-inf', 'nan'."""
    x = float(x)
    if math.isnan(x):
        return "nan"
    if math.isinf(x):
        return "inf" if x > 0 else "-inf"
    return x


def stamp(header):
    return [int(header.stamp.sec), int(header.stamp.nanosec)]


def pose(p):
    return [
        num(p.position.x),
        num(p.position.y),
        num(p.position.z),
        num(p.orientation.x),
        num(p.orientation.y),
        num(p.orientation.z),
        num(p.orientation.w),
    ]


def scan(m):
    return {
        "stamp": stamp(m.header),
        "frame_id": m.header.frame_id,
        "angle_min": num(m.angle_min),
        "angle_max": num(m.angle_max),
        "angle_increment": num(m.angle_increment),
        "time_increment": num(m.time_increment),
        "scan_time": num(m.scan_time),
        "range_min": num(m.range_min),
        "range_max": num(m.range_max),
        "ranges": [num(r) for r in m.ranges],
        "intensities": len(m.intensities),
    }


def read_rosbags(path):
    from rosbags.highlevel import AnyReader

    out = {"topics": {}, "scans": [], "estimates": [], "truths": [], "tf": [], "tf_static": [], "maps": []}
    with AnyReader([path]) as reader:
        for c in reader.connections:
            qos = getattr(c.ext, "offered_qos_profiles", [])
            durability = [q.durability.name for q in qos]
            out["topics"][c.topic] = {"type": c.msgtype, "count": 0, "durability": durability}
        for connection, _timestamp, raw in reader.messages():
            msg = reader.deserialize(raw, connection.msgtype)
            out["topics"][connection.topic]["count"] += 1
            topic = connection.topic
            if topic == "/scan":
                out["scans"].append(scan(msg))
            elif topic in ("/pose_estimate", "/pose_truth"):
                key = "estimates" if topic.endswith("estimate") else "truths"
                out[key].append(
                    {"stamp": stamp(msg.header), "frame_id": msg.header.frame_id, "pose": pose(msg.pose)}
                )
            elif topic in ("/tf", "/tf_static"):
                for t in msg.transforms:
                    tr = t.transform
                    out["tf" if topic == "/tf" else "tf_static"].append(
                        {
                            "stamp": stamp(t.header),
                            "parent": t.header.frame_id,
                            "child": t.child_frame_id,
                            "translation": [num(tr.translation.x), num(tr.translation.y), num(tr.translation.z)],
                            "rotation": [num(tr.rotation.x), num(tr.rotation.y), num(tr.rotation.z), num(tr.rotation.w)],
                        }
                    )
            elif topic == "/map":
                info = msg.info
                out["maps"].append(
                    {
                        "stamp": stamp(msg.header),
                        "frame_id": msg.header.frame_id,
                        "resolution": num(info.resolution),
                        "width": int(info.width),
                        "height": int(info.height),
                        "origin": pose(info.origin),
                        "data": [int(v) for v in msg.data],
                    }
                )
    # Only the first and last scans in full; the stamps of all.
    scans = out.pop("scans")
    out["scan_stamps"] = [s["stamp"] for s in scans]
    out["first_scan"] = scans[0] if scans else None
    out["last_scan"] = scans[-1] if scans else None
    return out


def read_mcap_ros2(path):
    """Message counts per topic as mcap-ros2-support decodes them, and the metadata names."""
    from mcap.reader import make_reader
    from mcap_ros2.decoder import DecoderFactory

    counts = {}
    with open(path, "rb") as f:
        reader = make_reader(f, decoder_factories=[DecoderFactory()])
        profile = reader.get_header().profile
        for _schema, channel, _message, decoded in reader.iter_decoded_messages():
            assert decoded is not None
            counts[channel.topic] = counts.get(channel.topic, 0) + 1
    with open(path, "rb") as f:
        metadata = [m.name for m in make_reader(f).iter_metadata()]
    return {"profile": profile, "counts": counts, "metadata": metadata}


def main():
    path = Path(sys.argv[1])
    out = read_rosbags(path)
    out["mcap_ros2"] = read_mcap_ros2(path)
    json.dump(out, sys.stdout)
    sys.stdout.write("\n")


if __name__ == "__main__":
    main()
