//! `quad12`: Study B's 12-DOF trotting quadruped with D-H legs
//! (`/work/shared/reference.md`), identical at its defaults to
//! `models/quad12.urdf` in every kinematic and inertial number.
//!
//! # Structure
//! Torso (box, the floating base; size and mass are the URDF's assumptions) and
//! four identical legs in the order LF, RF, RH, LH. Per leg, in q order:
//! `hip_yaw` θ1 (about the hip's z), `hip_pitch` θ2 (y), `knee` θ3 (y); links
//! `{leg}_hip`, `{leg}_thigh`, `{leg}_shank` and the massless `{leg}_foot`
//! fixed at the shank's tip.
//!
//! Frames: the hip frame sits at the torso corner `(±mount_x, ±mount_y,
//! mount_z)` (+x front, +y left), turned about z by the leg yaw (LF
//! +`front_yaw`, RF −`front_yaw`, RH −`hind_yaw`, LH +`hind_yaw`), so each
//! leg's x axis points outward. The legs are identical, not mirrored: the
//! robot is symmetric under a half turn about z. Inside a leg (the study's D-H
//! chain): the thigh frame is `l1` along the hip's y; the knee is `l2` along
//! the thigh's x; the foot is `l3` along the shank's x. At θ2 = θ3 = 0 the leg
//! is stretched out horizontally; positive θ2, θ3 swing it down.
//!
//! The foot carries a massless rubber-pad sphere of `foot.radius_m` centred on
//! the foot frame (as in `models/quad12.xml`). The foot contact point
//! (`foot_points`) is the pad's surface one radius further along the shank
//! (`(radius, 0, 0)` in the foot frame): the lowest point of the pad whenever
//! the shank is vertical, as in the nominal stance.
//!
//! # Inertia and what follows a length change
//! The study's table (mass, CoM, inertia about the CoM) is used as given, in
//! the URDF's frames: hip CoM `(0, l1/2, 0)`, inertia diag(1, 1.5, 2)·10⁻⁵ kg·m²;
//! thigh CoM `(l2/2, 0, 0)`, diag(5, 6, 7)·10⁻⁵; shank CoM `(l3/2, 0, 0)`,
//! diag(3, 4, 5)·10⁻⁵. When a link length changes by the factor `s`, the link
//! is stretched along its length axis (y for the hip, x for the thigh and
//! shank) at constant density:
//! - its CoM stays at mid-length (scales with `s`);
//! - its mass, unless given, scales with `s` (same cross-section, same density);
//! - its second moments of mass about the CoM along the length axis scale with
//!   `s²` times the mass ratio, the other two with the mass ratio only; the
//!   inertia tensor is rebuilt from them (`I_xx = P_yy + P_zz`, …). An
//!   overridden mass at unchanged length therefore scales the whole tensor.
//!
//! The torso's inertia is the solid-box formula for its mass and size; its
//! mass, unless given, follows the box volume.
//!
//! # Parameters
//! | path | default | unit | meaning |
//! |---|---|---|---|
//! | `torso.size_x_m` | 0.3 | m | torso box length (x) |
//! | `torso.size_y_m` | 0.15 | m | torso box width (y) |
//! | `torso.size_z_m` | 0.05 | m | torso box height (z) |
//! | `torso.mass_kg` | 2 | kg | torso mass (follows the box volume unless given) |
//! | `mount.x_m` | 0.15 | m | hip mount distance ahead of / behind the torso centre (study: a) |
//! | `mount.y_m` | 0.075 | m | hip mount distance left / right of the torso centre (study: b) |
//! | `mount.z_m` | 0 | m | hip mount height above the torso centre (study: c) |
//! | `leg.front_yaw_rad` | 0.7853981634 | rad | outward turn of the front legs (π/4 to the URDF's 10 digits) |
//! | `leg.hind_yaw_rad` | 2.35619449 | rad | outward turn of the hind legs (3π/4 to the URDF's 9 digits) |
//! | `hip.length_m` | 0.05 | m | l1: hip-yaw to hip-pitch offset, across the leg |
//! | `hip.mass_kg` | 0.5 | kg | hip link mass (follows l1 unless given) |
//! | `thigh.length_m` | 0.1 | m | l2: hip pitch to knee |
//! | `thigh.mass_kg` | 1.2 | kg | thigh mass (follows l2 unless given) |
//! | `shank.length_m` | 0.08 | m | l3: knee to foot |
//! | `shank.mass_kg` | 0.8 | kg | shank mass (follows l3 unless given) |
//! | `foot.radius_m` | 0.01 | m | radius of the massless foot pad (the MJCF's) |
//! | `joint.limit_rad` | 3.14159 | rad | symmetric position limit of every joint (the URDF's) |
//! | `actuator.effort_limit_nm` | 3 | N·m | torque limit of every joint (ASSUMPTION) |
//! | `actuator.velocity_limit_rad_s` | 6 | rad/s | speed limit of every joint (ASSUMPTION) |
//!
//! The leg yaws default to the URDF's printed digits rather than to π/4 and
//! 3π/4 so that the built-in and the shared URDF are the same robot to the
//! last bit (the difference, 2·10⁻¹⁰ rad, is far below any physical effect).
//!
//! # Actuator assumptions
//! The study sizes the knee against a Futaba S3003 (0.3 N·m at 6 V, about
//! 0.19 s per 60°, i.e. 5.5 rad/s). With the study's own mass table the robot
//! weighs 12 kg: a standing leg carries about 29 N, so 0.3 N·m would allow a
//! lever of 10 mm only, and the nominal stance below needs about 1.4 N·m at
//! the hip pitch. The default torque limit, 3 N·m, is that of the high-torque
//! hobby-servo class (30–35 kg·cm digital servos). It is **not** enough for a
//! trot's two-foot support: each stance foot then carries about 59 N, 87 mm
//! out from the hip pitch axis, and the hip pitch needs 3.85 N·m (measured
//! under the VMC walker; `docs/study_b_trot.md`), so walking scenarios raise
//! it (6–10 N·m for VMC, 20 N·m in `scenarios/small_trot.toml` so that the
//! prescribed trot's foot-strike peaks show unclipped). The speed limit,
//! 6 rad/s (0.17 s per 60°), is the same class's speed at 6 V.

use super::links::box_torso;
use super::params::{Domain, ParamSpec, Values};
use crate::actuator_model::{ActuatorDefaults, ActuatorKind, MotorGear, MotorRating, ServoParams};
use crate::description::{Geometry, JointDesc, JointKind, LinkDesc, RobotDescription, Shape};
use crate::sensors::{ONE_G_MPS2, SensorSpec};
use crate::spatial::{Transform, rot_from_rpy};
use glam::{DMat3, DVec3};

/// Robot name.
pub const NAME: &str = "quad12";

/// Legs in q order: name, mount signs (x, y), and whether the leg is a front leg
/// (front legs turn by `leg.front_yaw_rad`, hind legs by `leg.hind_yaw_rad`),
/// with the sign of the turn.
const LEGS: [(&str, f64, f64, bool, f64); 4] = [
    ("LF", 1.0, 1.0, true, 1.0),
    ("RF", 1.0, -1.0, true, -1.0),
    ("RH", -1.0, -1.0, false, -1.0),
    ("LH", -1.0, 1.0, false, 1.0),
];

/// Standing joint angles per leg `[hip_yaw, hip_pitch, knee]` (rad): the
/// `stand` keyframe of `models/quad12.xml`. The thigh points 30° below the
/// horizontal, outward; the knee bends 60° more so the shank is vertical and
/// the foot stands right below the knee, 0.13 m below the hip, 87 mm out along
/// the leg. The knee then carries almost no static torque and the hip pitch
/// about 1.4 N·m.
pub const STANCE_LEG_RAD: [f64; 3] = [
    0.0,
    std::f64::consts::FRAC_PI_6,
    std::f64::consts::FRAC_PI_3,
];

/// Degrees to radians.
const DEG: f64 = std::f64::consts::PI / 180.0;

/// quad12's sensors (`docs/sensors.md`), as on Study B's 12 kg hobby-servo
/// robot: an InvenSense MPU-6050-class IMU (±8 g, ±500 °/s, 16 bit;
/// 400 µg/√Hz, 0.005 °/s/√Hz), 10-bit servo potentiometers over 300°
/// (5.1 mrad) with velocity by differencing (10 ms filter), foot switches at
/// 8/4 N.
pub const SENSORS: SensorSpec = SensorSpec {
    accel_noise_density: 400e-6 * ONE_G_MPS2,
    gyro_noise_density: 0.005 * DEG,
    accel_range_mps2: 8.0 * ONE_G_MPS2,
    gyro_range_radps: 500.0 * DEG,
    encoder_resolution_rad: 300.0 * DEG / 1024.0,
    encoder_noise_std_rad: 2e-3,
    encoder_velocity_filter_s: 0.01,
    contact_on_threshold_n: 8.0,
    contact_off_threshold_n: 4.0,
    contact_noise_std_n: 1.0,
    contact_force_output: false,
};

/// Futaba S3003 stall torque (N·m): Study B's 300 N·mm at 6 V (the figure
/// its knee is sized against; see `docs/actuators.md` for the datasheet's).
pub const S3003_STALL_TORQUE_NM: f64 = 0.3;
/// Futaba S3003 no-load speed at 6 V (rad/s): 0.19 s per 60° (datasheet;
/// 0.23 s per 60° at 4.8 V).
pub const S3003_NO_LOAD_SPEED_RADPS: f64 = std::f64::consts::FRAC_PI_3 / 0.19;

/// quad12's actuators (`docs/actuators.md`): ideal sources by default
/// (Study B imposes the joints' motion). DC motor: a hobby servo's motor and
/// gear train, N = 250 with a 5·10⁻⁸ kg·m² rotor (reflected
/// 3.1·10⁻³ kg·m²), 0.02 N·m Coulomb friction, 200 Hz bandwidth, no
/// latency, stalling at the joint's effort limit and running free at its
/// velocity limit / 0.75 (3 N·m, 8 rad/s unless the `actuator.*`
/// parameters change the limits). Servo: Study B's Futaba S3003 at 6 V
/// whatever the joint's limits: τ_s = 0.3 N·m, ω₀ = 60°/0.19 s =
/// 5.51 rad/s, the same gear train, a 300 Hz PD of 1.72 N·m/rad (full
/// torque at 10° of error) and 0.05 N·m·s/rad.
pub const ACTUATORS: ActuatorDefaults = ActuatorDefaults {
    kind: ActuatorKind::Ideal,
    gear: MotorGear {
        gear_ratio: 250.0,
        rotor_inertia_kgm2: 5e-8,
        viscous_nms_per_rad: 0.0,
        coulomb_nm: 0.02,
        bandwidth_hz: 200.0,
        latency_ticks: 0,
    },
    servo_rating: Some(MotorRating {
        stall_torque_nm: S3003_STALL_TORQUE_NM,
        no_load_speed_radps: S3003_NO_LOAD_SPEED_RADPS,
    }),
    servo: ServoParams {
        kp_nm_per_rad: S3003_STALL_TORQUE_NM / 10f64.to_radians(),
        kd_nms_per_rad: 0.05,
        rate_hz: 300.0,
    },
};

/// Principal inertias about the CoM (kg·m², link axes) of the study's links at
/// their default lengths: hip, thigh, shank.
const HIP_INERTIA: DVec3 = DVec3::new(1e-5, 1.5e-5, 2e-5);
const THIGH_INERTIA: DVec3 = DVec3::new(5e-5, 6e-5, 7e-5);
const SHANK_INERTIA: DVec3 = DVec3::new(3e-5, 4e-5, 5e-5);

/// Radii (m) of the visual capsules of the hip, thigh and shank (the MJCF's).
const VISUAL_RADII_M: [f64; 3] = [0.01, 0.01, 0.008];

/// The parameter table (see the module docs).
#[expect(
    clippy::approx_constant,
    reason = "the URDF's printed digits of π/4, 3π/4 and its ±3.14159 joint range, kept so the built-in equals the URDF"
)]
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec::new(
        "torso.size_x_m",
        0.3,
        "m",
        "torso box length (x)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "torso.size_y_m",
        0.15,
        "m",
        "torso box width (y)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "torso.size_z_m",
        0.05,
        "m",
        "torso box height (z)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "torso.mass_kg",
        2.0,
        "kg",
        "torso mass (follows the box volume unless given)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "mount.x_m",
        0.15,
        "m",
        "hip mount distance ahead of / behind the torso centre (study: a)",
        Domain::Finite,
    ),
    ParamSpec::new(
        "mount.y_m",
        0.075,
        "m",
        "hip mount distance left / right of the torso centre (study: b)",
        Domain::Finite,
    ),
    ParamSpec::new(
        "mount.z_m",
        0.0,
        "m",
        "hip mount height above the torso centre (study: c)",
        Domain::Finite,
    ),
    ParamSpec::new(
        "leg.front_yaw_rad",
        0.7853981634,
        "rad",
        "outward turn of the front legs (π/4 to the URDF's 10 digits)",
        Domain::Finite,
    ),
    ParamSpec::new(
        "leg.hind_yaw_rad",
        2.35619449,
        "rad",
        "outward turn of the hind legs (3π/4 to the URDF's 9 digits)",
        Domain::Finite,
    ),
    ParamSpec::new(
        "hip.length_m",
        0.05,
        "m",
        "l1: hip-yaw to hip-pitch offset, across the leg",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "hip.mass_kg",
        0.5,
        "kg",
        "hip link mass (follows l1 unless given)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "thigh.length_m",
        0.1,
        "m",
        "l2: hip pitch to knee",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "thigh.mass_kg",
        1.2,
        "kg",
        "thigh mass (follows l2 unless given)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "shank.length_m",
        0.08,
        "m",
        "l3: knee to foot",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "shank.mass_kg",
        0.8,
        "kg",
        "shank mass (follows l3 unless given)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "foot.radius_m",
        0.01,
        "m",
        "radius of the massless foot pad (the MJCF's)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "joint.limit_rad",
        3.14159,
        "rad",
        "symmetric position limit of every joint (the URDF's)",
        Domain::Positive,
    ),
    ParamSpec::new(
        "actuator.effort_limit_nm",
        3.0,
        "N·m",
        "torque limit of every joint (ASSUMPTION: high-torque hobby servo)",
        Domain::Positive,
    ),
    ParamSpec::new(
        "actuator.velocity_limit_rad_s",
        6.0,
        "rad/s",
        "speed limit of every joint (ASSUMPTION: hobby servo at 6 V)",
        Domain::Positive,
    ),
];

/// Inertia (kg·m², about the CoM) of a link with principal inertias `i0` at its
/// default length, stretched by `s` along axis `axis` (0 = x, 1 = y, 2 = z) and
/// carrying `mass_ratio` times its default mass (see the module docs).
pub fn stretched_inertia(i0: DVec3, axis: usize, s: f64, mass_ratio: f64) -> DMat3 {
    // second moment of mass along the length axis: P_aa = (I_bb + I_cc − I_aa) / 2
    let p_aa = 0.5 * (i0.element_sum() - 2.0 * i0[axis]);
    let mut d = i0;
    for k in 0..3 {
        if k != axis {
            d[k] += (s * s - 1.0) * p_aa;
        }
    }
    DMat3::from_diagonal(d * mass_ratio)
}

/// A capsule (visual only) from the link origin to `tip` (a point on a link axis).
fn capsule_to(tip: DVec3, radius_m: f64) -> Geometry {
    // Shape capsules lie along z: turn z onto x (pitch +π/2) or onto y (roll −π/2).
    let rpy = if tip.y != 0.0 {
        DVec3::new(-std::f64::consts::FRAC_PI_2, 0.0, 0.0)
    } else {
        DVec3::new(0.0, std::f64::consts::FRAC_PI_2, 0.0)
    };
    Geometry {
        origin: Transform::new(rot_from_rpy(rpy), 0.5 * tip),
        shape: Shape::Capsule {
            radius_m,
            length_m: tip.length(),
        },
    }
}

/// Builds the description from resolved parameters.
pub(crate) fn build(p: &Values) -> RobotDescription {
    let mount = DVec3::new(p.get("mount.x_m"), p.get("mount.y_m"), p.get("mount.z_m"));
    let (front_yaw, hind_yaw) = (p.get("leg.front_yaw_rad"), p.get("leg.hind_yaw_rad"));
    let foot_r = p.get("foot.radius_m");
    let limit = p.get("joint.limit_rad");
    let effort = p.get("actuator.effort_limit_nm");
    let velocity = p.get("actuator.velocity_limit_rad_s");

    // (length path, mass path, default inertia, length axis, link-frame tip direction)
    let parts = [
        ("hip.length_m", "hip.mass_kg", HIP_INERTIA, 1, DVec3::Y),
        (
            "thigh.length_m",
            "thigh.mass_kg",
            THIGH_INERTIA,
            0,
            DVec3::X,
        ),
        (
            "shank.length_m",
            "shank.mass_kg",
            SHANK_INERTIA,
            0,
            DVec3::X,
        ),
    ];
    // per part: (length, mass, CoM, inertia)
    let links: Vec<(f64, f64, DVec3, DMat3)> = parts
        .iter()
        .map(|&(lp, mp, i0, axis, dir)| {
            let s = p.ratio(lp);
            let mass = p.mass_following(mp, s);
            let length = p.get(lp);
            let inertia = stretched_inertia(i0, axis, s, mass / p.default_of(mp));
            (length, mass, dir * (0.5 * length), inertia)
        })
        .collect();

    let mut d = RobotDescription::new(NAME);
    d.links.push(box_torso(p));
    let joint = |name: String, kind: JointKind, parent: &str, child: &str, at: Transform| {
        let j = JointDesc::new(name, kind, parent, child, at);
        if matches!(kind, JointKind::Fixed) {
            return j;
        }
        JointDesc {
            limits: Some((-limit, limit)),
            effort_limit: effort,
            velocity_limit: velocity,
            ..j
        }
    };
    for (leg, sx, sy, front, yaw_sign) in LEGS {
        let names = [
            format!("{leg}_hip"),
            format!("{leg}_thigh"),
            format!("{leg}_shank"),
        ];
        let foot = format!("{leg}_foot");
        for (k, (name, &(length, mass, com, inertia))) in names.iter().zip(&links).enumerate() {
            let tip = parts[k].4 * length;
            d.links.push(LinkDesc {
                name: name.clone(),
                mass_kg: mass,
                com_m: com,
                inertia_kgm2: Some(inertia),
                collision: Vec::new(),
                visual: vec![capsule_to(tip, VISUAL_RADII_M[k])],
            });
        }
        let pad = Geometry {
            origin: Transform::IDENTITY,
            shape: Shape::Sphere { radius_m: foot_r },
        };
        d.links.push(LinkDesc {
            inertia_kgm2: Some(DMat3::ZERO),
            collision: vec![pad.clone()],
            visual: vec![pad],
            ..LinkDesc::new(foot.clone())
        });

        let yaw = yaw_sign * if front { front_yaw } else { hind_yaw };
        let at_mount = Transform::from_xyz_rpy(
            DVec3::new(sx * mount.x, sy * mount.y, mount.z),
            DVec3::new(0.0, 0.0, yaw),
        );
        let revolute = |axis| JointKind::Revolute { axis };
        let (l1, l2, l3) = (links[0].0, links[1].0, links[2].0);
        d.joints.push(joint(
            format!("{leg}_hip_yaw"),
            revolute(DVec3::Z),
            "torso",
            &names[0],
            at_mount,
        ));
        d.joints.push(joint(
            format!("{leg}_hip_pitch"),
            revolute(DVec3::Y),
            &names[0],
            &names[1],
            Transform::from_translation(DVec3::new(0.0, l1, 0.0)),
        ));
        d.joints.push(joint(
            format!("{leg}_knee"),
            revolute(DVec3::Y),
            &names[1],
            &names[2],
            Transform::from_translation(DVec3::new(l2, 0.0, 0.0)),
        ));
        d.joints.push(joint(
            format!("{leg}_foot_fixed"),
            JointKind::Fixed,
            &names[2],
            &foot,
            Transform::from_translation(DVec3::new(l3, 0.0, 0.0)),
        ));
        d.feet.push(foot.clone());
        d.foot_points.push((foot, DVec3::new(foot_r, 0.0, 0.0)));
    }
    d
}
