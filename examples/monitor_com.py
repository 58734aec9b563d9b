"""Prints the centre of mass of every robot of a running quadsim world, live.

    quadsim run scenarios/trot.toml --world-name demo &
    python3 examples/monitor_com.py demo [N]

Reads quadsim/<world>/frames with the iceoryx2 package (pip install iceoryx2)
and ctypes (examples/quadsim_frame.py); prints N instants (default: until the
world ends) as `robot t_s x y z` (m, world)."""

import ctypes
import sys
import time

import iceoryx2 as iox2

from quadsim_frame import RobotFrame, check_layout, frames, node, open_service, read_header


def main():
    check_layout()
    world = sys.argv[1]
    limit = int(sys.argv[2]) if len(sys.argv) > 2 else None
    n = node()
    header_sub = (
        open_service(n, f"quadsim/{world}/header", iox2.Slice[ctypes.c_uint8], 10.0)
        .subscriber_builder()
        .create()
    )
    frame_sub = (
        open_service(n, f"quadsim/{world}/frames", iox2.Slice[RobotFrame], 10.0)
        .subscriber_builder()
        .create()
    )
    header = read_header(header_sub, 10.0)
    names = [r["name"] for r in header["robots"]]
    printed, last = 0, time.monotonic()
    while limit is None or printed < limit:
        sample = frame_sub.receive()
        if sample is None:
            if time.monotonic() - last > 2.0:
                break  # the world ended
            time.sleep(0.0005)
            continue
        last = time.monotonic()
        for f in frames(sample, len(header["robots"])):
            x, y, z = f.com_m
            print(f"{names[f.robot_index]} {f.time_s:.4f} {x:.6f} {y:.6f} {z:.6f}", flush=True)
        printed += 1


if __name__ == "__main__":
    main()
