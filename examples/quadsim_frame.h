/* quadsim's shared-memory messages (docs/monitor.md), layout version 1.
 *
 * quadsim_robot_frame: one robot at one instant on quadsim/<world>/frames
 * (iceoryx2 type name "quadsim.RobotFrame.v1"; a sample is an array of
 * n_robots frames). quadsim_robot_command: one robot's command on
 * quadsim/<world>/commands ("quadsim.RobotCommand.v1").
 *
 * Units SI; frames: world is z up, "base" is the root link's frame origin,
 * twists of that origin in world axes. Missing values are NaN.
 * tests/monitor_c_header.rs compiles a program with this header and checks
 * every offset against the Rust structs. */
#ifndef QUADSIM_FRAME_H
#define QUADSIM_FRAME_H

#include <stddef.h>
#include <stdint.h>

#define QUADSIM_LAYOUT_VERSION 1u
#define QUADSIM_COMMAND_LAYOUT_VERSION 1u
#define QUADSIM_FRAME_TYPE_NAME "quadsim.RobotFrame.v1"
#define QUADSIM_COMMAND_TYPE_NAME "quadsim.RobotCommand.v1"
#define QUADSIM_MAX_DOF 24
#define QUADSIM_MAX_FEET 4

#define QUADSIM_MODE_JOINT 1u    /* tau = tau_ff + kp (q* - q) + kd (qd* - qd) */
#define QUADSIM_MODE_TORQUE 2u   /* tau = tau_ff */
#define QUADSIM_MODE_VELOCITY 3u /* walker: forward, lateral, yaw rate */

typedef struct quadsim_robot_frame {
    uint32_t layout_version;      /* QUADSIM_LAYOUT_VERSION; reject others */
    uint32_t robot_index;         /* index in the header's robots */
    uint64_t tick;                /* step index j */
    double time_s;                /* s, j * dt */
    uint32_t n_dof;               /* actuated joints */
    uint32_t n_feet;              /* feet */
    uint32_t contact_flags;       /* bit i: foot i touches the ground */
    uint32_t slip_flags;          /* bit i: foot i slips */
    double base_position_m[3];    /* m, world */
    double base_orientation_xyzw[4]; /* quaternion base -> world */
    double base_linear_mps[3];    /* m/s, world axes */
    double base_angular_radps[3]; /* rad/s, world axes */
    double rpy_rad[3];            /* rad, R = Rz(yaw) Ry(pitch) Rx(roll) */
    double com_m[3];              /* m, world */
    double com_velocity_mps[3];   /* m/s, world */
    double joint_q_rad[QUADSIM_MAX_DOF];
    double joint_qd_radps[QUADSIM_MAX_DOF];
    double joint_q_desired_rad[QUADSIM_MAX_DOF];
    double joint_qd_desired_radps[QUADSIM_MAX_DOF];
    double joint_tau_nm[QUADSIM_MAX_DOF];         /* after saturation */
    double joint_tau_desired_nm[QUADSIM_MAX_DOF]; /* command before saturation */
    double foot_force_n[QUADSIM_MAX_FEET][3];     /* N, world */
    double gait_phase[QUADSIM_MAX_FEET];          /* [0, 1) or NaN */
} quadsim_robot_frame;

typedef struct quadsim_robot_command {
    uint32_t layout_version; /* QUADSIM_COMMAND_LAYOUT_VERSION */
    uint32_t robot_index;
    uint64_t tick;           /* first step index it applies to */
    uint32_t mode;           /* QUADSIM_MODE_* */
    uint32_t n_dof;
    double q_target_rad[QUADSIM_MAX_DOF];
    double qd_target_radps[QUADSIM_MAX_DOF];
    double kp_nm_per_rad[QUADSIM_MAX_DOF];
    double kd_nms_per_rad[QUADSIM_MAX_DOF];
    double tau_ff_nm[QUADSIM_MAX_DOF];
    double velocity[3];      /* forward m/s, lateral m/s, yaw rate rad/s */
} quadsim_robot_command;

_Static_assert(sizeof(quadsim_robot_frame) == 1496, "RobotFrame v1 is 1496 bytes");
_Static_assert(offsetof(quadsim_robot_frame, gait_phase) == 1464, "RobotFrame v1 layout");
_Static_assert(sizeof(quadsim_robot_command) == 1008, "RobotCommand v1 is 1008 bytes");
_Static_assert(offsetof(quadsim_robot_command, velocity) == 984, "RobotCommand v1 layout");

#endif
