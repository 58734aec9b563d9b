"""An external controller: makes quad16 stand through quad16's joints.

    quadsim run scenarios/stand_external.toml --world-name demo --lockstep &
    python3 examples/stand_external.py demo

Joint PD toward the first frame's joint angles with scenarios/stand.toml's
gains, sent on quadsim/<world>/commands in lockstep: a limp command for tick
0, then for each frame at tick t the command for tick t + N (N: the header's
every_steps). Ends when the world stops sending; prints the torso height."""

import ctypes
import sys
import time

import iceoryx2 as iox2

from quadsim_frame import (
    MODE_JOINT,
    MODE_TORQUE,
    RobotCommand,
    RobotFrame,
    check_layout,
    frames,
    node,
    open_service,
    read_header,
)

KP = [300.0, 300.0, 300.0, 100.0]  # hip roll, hip pitch, knee, ankle (N·m/rad)
KD = [5.0, 5.0, 5.0, 0.5]  # (N·m·s/rad)


def main():
    check_layout()
    world = sys.argv[1]
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
    publisher = (
        open_service(n, f"quadsim/{world}/commands", iox2.Slice[RobotCommand], 10.0)
        .publisher_builder()
        .initial_max_slice_len(1)
        .create()
    )
    header = read_header(header_sub, 10.0)
    every = header["every_steps"]
    nj = header["robots"][0]["dof"]

    def send(cmd):
        sample = publisher.loan_slice_uninit(1)
        sample.payload()[0] = cmd
        sample.assume_init().send()

    cmd = RobotCommand(layout_version=1, robot_index=0, tick=0, mode=MODE_TORQUE, n_dof=nj)
    send(cmd)
    target, z0, z, last = None, None, None, time.monotonic()
    while True:
        sample = frame_sub.receive()
        if sample is None:
            if time.monotonic() - last > 2.0:
                break  # the run ended
            continue
        last = time.monotonic()
        f = frames(sample, len(header["robots"]))[0]
        if target is None:
            target = list(f.joint_q_rad)
            z0 = f.base_position_m[2]
        z = f.base_position_m[2]
        cmd = RobotCommand(layout_version=1, robot_index=0, tick=f.tick + every, mode=MODE_JOINT, n_dof=nj)
        for j in range(nj):
            cmd.q_target_rad[j] = target[j]
            cmd.kp_nm_per_rad[j] = KP[j % 4]
            cmd.kd_nms_per_rad[j] = KD[j % 4]
        send(cmd)
    print(f"torso height {z0:.4f} m -> {z:.4f} m")


if __name__ == "__main__":
    main()
