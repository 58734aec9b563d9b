/* Prints "<struct>.<field> <offset> <size>" for every field of
 * quadsim_frame.h, and each struct's size; tests/monitor_c_header.rs
 * compares the lines with the Rust structs. */
#include <stdio.h>
#include "quadsim_frame.h"

#define F(T, f) printf("%s.%s %zu %zu\n", #T, #f, offsetof(T, f), sizeof(((T *)0)->f))

int main(void) {
    F(quadsim_robot_frame, layout_version);
    F(quadsim_robot_frame, robot_index);
    F(quadsim_robot_frame, tick);
    F(quadsim_robot_frame, time_s);
    F(quadsim_robot_frame, n_dof);
    F(quadsim_robot_frame, n_feet);
    F(quadsim_robot_frame, contact_flags);
    F(quadsim_robot_frame, slip_flags);
    F(quadsim_robot_frame, base_position_m);
    F(quadsim_robot_frame, base_orientation_xyzw);
    F(quadsim_robot_frame, base_linear_mps);
    F(quadsim_robot_frame, base_angular_radps);
    F(quadsim_robot_frame, rpy_rad);
    F(quadsim_robot_frame, com_m);
    F(quadsim_robot_frame, com_velocity_mps);
    F(quadsim_robot_frame, joint_q_rad);
    F(quadsim_robot_frame, joint_qd_radps);
    F(quadsim_robot_frame, joint_q_desired_rad);
    F(quadsim_robot_frame, joint_qd_desired_radps);
    F(quadsim_robot_frame, joint_tau_nm);
    F(quadsim_robot_frame, joint_tau_desired_nm);
    F(quadsim_robot_frame, foot_force_n);
    F(quadsim_robot_frame, gait_phase);
    printf("quadsim_robot_frame %zu\n", sizeof(quadsim_robot_frame));
    F(quadsim_robot_command, layout_version);
    F(quadsim_robot_command, robot_index);
    F(quadsim_robot_command, tick);
    F(quadsim_robot_command, mode);
    F(quadsim_robot_command, n_dof);
    F(quadsim_robot_command, q_target_rad);
    F(quadsim_robot_command, qd_target_radps);
    F(quadsim_robot_command, kp_nm_per_rad);
    F(quadsim_robot_command, kd_nms_per_rad);
    F(quadsim_robot_command, tau_ff_nm);
    F(quadsim_robot_command, velocity);
    printf("quadsim_robot_command %zu\n", sizeof(quadsim_robot_command));
    return 0;
}
