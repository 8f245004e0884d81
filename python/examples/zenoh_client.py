"""An outside client of a running swarm: subscribes to every UAV's broadcast state over Zenoh
(the `eclipse-zenoh` package) and prints what it receives. It uses only the wire schema
(docs/wire.md), not the proxform package.

    python examples/zenoh_client.py --connect tcp/127.0.0.1:7447 --swarm lab [--seconds 10]

Start a swarm first, for instance:

    proxform run --distributed --listen tcp/127.0.0.1:7447 --swarm lab --start-delay-s 3
"""

from __future__ import annotations

import argparse
import struct
import threading
import time

import zenoh

#: Header: magic "PXF", schema version, kind, three zero bytes.
HEADER = struct.Struct("<3sBB3x")
#: A state message's body: UAV (from 1), step, time (s), 9 state numbers (SI, radians), and
#: whether its agent is rejoining (back after flying without decisions), 7 zero bytes.
STATE = struct.Struct("<IQd9dB7x")
VERSION, KIND_STATE = 1, 1
#: A sealed flight's messages end with a 32-byte HMAC-SHA256 tag (docs/wire.md, "Sealed
#: flights"): readable by anyone, writable only with the flight's key.
TAG = 32


def decode_state(payload: bytes) -> tuple[int, int, float, tuple[float, ...]] | None:
    """(uav, step, t_s, state) of a state message (sealed or not), or None for anything else."""
    if len(payload) not in (HEADER.size + STATE.size, HEADER.size + STATE.size + TAG):
        return None
    magic, version, kind = HEADER.unpack_from(payload)
    if magic != b"PXF" or version != VERSION or kind != KIND_STATE:
        return None
    uav, k, t, *state, _rejoining = STATE.unpack_from(payload, HEADER.size)
    return uav, k, t, tuple(state)


def listen(connect: str, swarm: str, seconds: float, ready: threading.Event | None = None) -> dict[int, list]:
    """Every state received from `swarm` within `seconds`, by UAV: lists of (step, t_s, state)."""
    conf = zenoh.Config()
    conf.insert_json5("mode", '"client"')
    conf.insert_json5("connect/endpoints", f'["{connect}"]')
    conf.insert_json5("scouting/multicast/enabled", "false")
    # Wait up to 10 s for the router (the swarm may still be starting).
    conf.insert_json5("connect/timeout_ms", "10000")
    received: dict[int, list] = {}
    lock = threading.Lock()

    def on_sample(sample: zenoh.Sample) -> None:
        m = decode_state(sample.payload.to_bytes())
        if m is not None:
            with lock:
                received.setdefault(m[0], []).append(m[1:])

    with zenoh.open(conf) as session:
        session.declare_subscriber(f"proxform/v1/{swarm}/uav/*/state", on_sample)
        if ready is not None:
            ready.set()
        time.sleep(seconds)
    with lock:
        return {u: list(v) for u, v in received.items()}


def main(argv: list[str] | None = None) -> dict[int, list]:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--connect", default="tcp/127.0.0.1:7447")
    ap.add_argument("--swarm", default="proxform")
    ap.add_argument("--seconds", type=float, default=10.0)
    args = ap.parse_args(argv)
    received = listen(args.connect, args.swarm, args.seconds)
    for uav in sorted(received):
        k, t, s = received[uav][-1]
        print(f"UAV{uav}: {len(received[uav])} states, last at t = {t:.1f} s: x {s[0]:.1f} y {s[1]:.1f} z {s[2]:.1f} m")
    return received


if __name__ == "__main__":
    main()
