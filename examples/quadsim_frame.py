"""ctypes mirrors of quadsim's shared-memory messages (docs/monitor.md),
layout version 1, for the iceoryx2 package from PyPI. The field order and
sizes are those of examples/quadsim_frame.h and the Rust structs;
`check_layout()` compares the offsets with the documented ones."""

import ctypes
import json
import time

import iceoryx2 as iox2

LAYOUT_VERSION = 1
MAX_DOF = 24
MAX_FEET = 4
MODE_JOINT, MODE_TORQUE, MODE_VELOCITY = 1, 2, 3

D3 = ctypes.c_double * 3
DOF = ctypes.c_double * MAX_DOF


class RobotFrame(ctypes.Structure):
    """One robot at one instant (quadsim.RobotFrame.v1)."""

    _fields_ = [
        ("layout_version", ctypes.c_uint32),
        ("robot_index", ctypes.c_uint32),
        ("tick", ctypes.c_uint64),
        ("time_s", ctypes.c_double),
        ("n_dof", ctypes.c_uint32),
        ("n_feet", ctypes.c_uint32),
        ("contact_flags", ctypes.c_uint32),
        ("slip_flags", ctypes.c_uint32),
        ("base_position_m", D3),
        ("base_orientation_xyzw", ctypes.c_double * 4),
        ("base_linear_mps", D3),
        ("base_angular_radps", D3),
        ("rpy_rad", D3),
        ("com_m", D3),
        ("com_velocity_mps", D3),
        ("joint_q_rad", DOF),
        ("joint_qd_radps", DOF),
        ("joint_q_desired_rad", DOF),
        ("joint_qd_desired_radps", DOF),
        ("joint_tau_nm", DOF),
        ("joint_tau_desired_nm", DOF),
        ("foot_force_n", D3 * MAX_FEET),
        ("gait_phase", ctypes.c_double * MAX_FEET),
    ]

    @staticmethod
    def type_name() -> str:
        return "quadsim.RobotFrame.v1"


class RobotCommand(ctypes.Structure):
    """One robot's command from `tick` on (quadsim.RobotCommand.v1)."""

    _fields_ = [
        ("layout_version", ctypes.c_uint32),
        ("robot_index", ctypes.c_uint32),
        ("tick", ctypes.c_uint64),
        ("mode", ctypes.c_uint32),
        ("n_dof", ctypes.c_uint32),
        ("q_target_rad", DOF),
        ("qd_target_radps", DOF),
        ("kp_nm_per_rad", DOF),
        ("kd_nms_per_rad", DOF),
        ("tau_ff_nm", DOF),
        ("velocity", D3),
    ]

    @staticmethod
    def type_name() -> str:
        return "quadsim.RobotCommand.v1"


def check_layout():
    """The sizes and a few offsets of docs/monitor.md."""
    assert ctypes.sizeof(RobotFrame) == 1496, ctypes.sizeof(RobotFrame)
    assert RobotFrame.gait_phase.offset == 1464
    assert RobotFrame.joint_q_rad.offset == 216
    assert ctypes.sizeof(RobotCommand) == 1008, ctypes.sizeof(RobotCommand)
    assert RobotCommand.velocity.offset == 984


def node():
    return iox2.NodeBuilder.new().create(iox2.ServiceType.Ipc)


def open_service(n, name, payload, timeout_s):
    """Opens `name`, waiting up to `timeout_s` for it to appear."""
    start = time.monotonic()
    while True:
        try:
            return (
                n.service_builder(iox2.ServiceName.new(name))
                .publish_subscribe(payload)
                .open()
            )
        except iox2.PublishSubscribeOpenError as e:
            if "DoesNotExist" not in repr(e) or time.monotonic() - start > timeout_s:
                raise SystemExit(f"cannot open {name}: {e!r}")
            time.sleep(0.02)


def read_header(subscriber, timeout_s):
    """The world header (JSON)."""
    start = time.monotonic()
    while time.monotonic() - start < timeout_s:
        sample = subscriber.receive()
        if sample is not None:
            p = sample.payload()
            return json.loads(bytes(p[i] for i in range(p.len())))
        time.sleep(0.005)
    raise SystemExit("no world header")


def frames(sample, n_robots):
    """Copies of the frames of one instant, checked for the layout version.

    `n_robots` is the header's robot count: iceoryx2's Python binding
    (0.10) reports the slice length of a sample published from Rust in bytes,
    so the length is taken from the header instead."""
    p = sample.payload()
    out = []
    for i in range(min(p.len(), n_robots)):
        f = RobotFrame()
        ctypes.memmove(ctypes.addressof(f), p.as_ptr() + i * ctypes.sizeof(RobotFrame), ctypes.sizeof(RobotFrame))
        out.append(f)
    for f in out:
        if f.layout_version != LAYOUT_VERSION:
            raise SystemExit(
                f"frame layout version {f.layout_version}, this reader knows {LAYOUT_VERSION}"
            )
    return out
