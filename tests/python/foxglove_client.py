"""A Foxglove WebSocket client for `quadsim monitor --foxglove` (the test
`foxglove_live` runs it; CI installs `websockets` pinned in `.ci/run`).

It connects on loopback, checks serverInfo and the advertised channels and
schemas, subscribes to `/tf`, `/scene` and the robot's channels, receives
messages until it has N, decodes the FrameTransforms (protobuf, decoded
here by field number, no generated code) and prints, as one JSON object,
every `/tf` message's log time and the torso's transform, for the test to
compare with `log.mcap`. It exits non-zero on any protocol error, and
gives up after --timeout seconds.

    python3 foxglove_client.py --port 8765 --robot rex --messages 100
"""

import argparse
import asyncio
import base64
import json
import struct
import sys

import websockets

SUBPROTOCOL = "foxglove.sdk.v1"

# what the client has seen so far, reported on a timeout
STATE = {}


def varint(buf, i):
    x, shift = 0, 0
    while True:
        b = buf[i]
        i += 1
        x |= (b & 0x7F) << shift
        shift += 7
        if b < 0x80:
            return x, i


def fields(buf):
    """(field number, wire type, value) of a protobuf message; LEN values are bytes."""
    i, out = 0, []
    while i < len(buf):
        key, i = varint(buf, i)
        num, wire = key >> 3, key & 7
        if wire == 0:
            v, i = varint(buf, i)
        elif wire == 1:
            v = struct.unpack_from("<d", buf, i)[0]
            i += 8
        elif wire == 2:
            n, i = varint(buf, i)
            v = bytes(buf[i : i + n])
            i += n
        elif wire == 5:
            v = struct.unpack_from("<f", buf, i)[0]
            i += 4
        else:
            raise ValueError(f"wire type {wire}")
        out.append((num, wire, v))
    return out


def vec(buf, names):
    """A foxglove.Vector3 / Quaternion: absent doubles are 0 (proto3)."""
    v = dict.fromkeys(names, 0.0)
    for num, wire, x in fields(buf):
        if wire == 1 and 1 <= num <= len(names):
            v[names[num - 1]] = x
    return [v[n] for n in names]


def frame_transforms(payload):
    """foxglove.FrameTransforms: transforms = 1; each FrameTransform has
    timestamp = 1, parent_frame_id = 2, child_frame_id = 3,
    translation = 4 (Vector3), rotation = 5 (Quaternion)."""
    out = []
    for num, _, t in fields(payload):
        if num != 1:
            continue
        tr = {"parent": "", "child": "", "t": [0.0] * 3, "q": [0.0, 0.0, 0.0, 1.0]}
        for n, _, x in fields(t):
            if n == 2:
                tr["parent"] = x.decode()
            elif n == 3:
                tr["child"] = x.decode()
            elif n == 4:
                tr["t"] = vec(x, "xyz")
            elif n == 5:
                tr["q"] = vec(x, "xyzw")
        out.append(tr)
    return out


async def run(args):
    url = f"ws://127.0.0.1:{args.port}"
    async with websockets.connect(url, subprotocols=[SUBPROTOCOL], max_size=None) as ws:
        assert ws.subprotocol == SUBPROTOCOL, ws.subprotocol
        info, channels = None, {}
        want = {"/tf", "/scene", f"/{args.robot}/base_pose", f"/{args.robot}/joint_states"}
        # serverInfo first, then the channels (advertised as they are made)
        while not (info and want <= {c["topic"] for c in channels.values()}):
            msg = json.loads(await ws.recv())
            if msg["op"] == "serverInfo":
                info = msg
            elif msg["op"] == "advertise":
                for c in msg["channels"]:
                    channels[c["id"]] = c
            STATE["topics"] = sorted(c["topic"] for c in channels.values())
        assert info["name"].startswith("quadsim"), info
        by_topic = {c["topic"]: c for c in channels.values()}
        expect = {
            "/tf": ("protobuf", "foxglove.FrameTransforms", "protobuf"),
            "/scene": ("json", "foxglove.SceneUpdate", "jsonschema"),
            f"/{args.robot}/base_pose": ("protobuf", "foxglove.PoseInFrame", "protobuf"),
            f"/{args.robot}/joint_states": ("protobuf", "quadsim.JointState", "protobuf"),
        }
        for topic, (enc, name, schema_enc) in expect.items():
            c = by_topic[topic]
            got = (c["encoding"], c["schemaName"], c.get("schemaEncoding"))
            assert got == (enc, name, schema_enc), (topic, got)
        # a protobuf schema is a FileDescriptorSet naming the message
        tf_schema = base64.b64decode(by_topic["/tf"]["schema"])
        assert b"FrameTransforms" in tf_schema and b"foxglove" in tf_schema
        subs = {i + 1: c for i, c in enumerate(by_topic[t] for t in sorted(want))}
        await ws.send(
            json.dumps(
                {
                    "op": "subscribe",
                    "subscriptions": [{"id": s, "channelId": c["id"]} for s, c in subs.items()],
                }
            )
        )
        received, counts, tf, scene = 0, {}, [], None
        while received < args.messages or scene is None:
            msg = await ws.recv()
            if isinstance(msg, str):
                m = json.loads(msg)
                if m["op"] == "advertise":
                    for c in m["channels"]:
                        channels[c["id"]] = c
                continue
            assert msg[0] == 0x01, f"opcode {msg[0]}"
            sub, log_time = struct.unpack_from("<IQ", msg, 1)
            payload = msg[13:]
            topic = subs[sub]["topic"]
            counts[topic] = counts.get(topic, 0) + 1
            received += 1
            STATE["counts"] = counts
            if topic == "/tf":
                torso = [
                    t
                    for t in frame_transforms(payload)
                    if t["child"] == f"{args.robot}/{args.torso}"
                ]
                assert len(torso) == 1, "one torso transform per /tf message"
                assert torso[0]["parent"] == "world"
                tf.append({"t_ns": log_time, "t": torso[0]["t"], "q": torso[0]["q"]})
            elif topic == "/scene":
                scene = json.loads(payload)
        entities = [e["id"] for e in scene["entities"]]
        assert f"{args.robot}/{args.torso}" in entities, entities[:5]
        second = None
        if args.then_robot:
            second = await follow(ws, channels, args)
        print(
            json.dumps(
                {
                    "server": info["name"],
                    "topics": sorted(by_topic),
                    "received": received,
                    "counts": counts,
                    "tf": tf,
                    "second": second,
                }
            )
        )


async def follow(ws, channels, args):
    """Stays connected while the first robot's world ends and another
    world, with robot `--then-robot`, begins: the first robot's channels
    must be unadvertised and the new robot's advertised, and its poses
    must arrive on the same connection.

    The `foxglove` crate (0.30) sends a channel's advertisement before it
    registers the channel for the client, so a subscription that answers
    at once can meet "Unknown channel ID" (a status message); the client
    subscribes again then, to the same channel (a few times at most), and
    reports how often."""
    first = {i for i, c in channels.items() if c["topic"].startswith(f"/{args.robot}/")}
    gone, topic, sub_id, received = set(), f"/{args.then_robot}/base_pose", 1000, 0
    target, resubscribed = None, 0

    async def subscribe():
        await ws.send(
            json.dumps(
                {"op": "subscribe", "subscriptions": [{"id": sub_id, "channelId": target}]}
            )
        )

    while received < 10:
        msg = await ws.recv()
        if isinstance(msg, str):
            m = json.loads(msg)
            if m["op"] == "unadvertise":
                gone.update(m["channelIds"])
            elif m["op"] == "advertise":
                for c in m["channels"]:
                    channels[c["id"]] = c
                    if c["topic"] == topic and target is None:
                        target = c["id"]
                        await subscribe()
            elif (
                m["op"] == "status"
                and target is not None
                and target not in gone
                and m.get("message") == f"Unknown channel ID: {target}"
                and resubscribed < 5
            ):
                resubscribed += 1
                await asyncio.sleep(0.05)
                await subscribe()
            STATE["second"] = {
                "gone": len(gone),
                "target": target,
                "received": received,
                "resubscribed": resubscribed,
            }
            continue
        sub = struct.unpack_from("<I", msg, 1)[0]
        if sub == sub_id:
            received += 1
    return {
        "robot": args.then_robot,
        "received": received,
        "first_channels_unadvertised": first <= gone,
        "resubscribed": resubscribed,
    }


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--port", type=int, required=True)
    p.add_argument("--robot", default="rex")
    p.add_argument("--torso", default="torso")
    p.add_argument("--messages", type=int, default=100)
    p.add_argument("--timeout", type=float, default=60.0)
    p.add_argument("--then-robot", default=None)
    args = p.parse_args()
    try:
        asyncio.run(asyncio.wait_for(run(args), args.timeout))
    except asyncio.TimeoutError:
        sys.exit(f"timed out after {args.timeout} s; seen: {json.dumps(STATE)}")


if __name__ == "__main__":
    main()
