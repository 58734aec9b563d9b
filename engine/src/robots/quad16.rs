//! `quad16`: Study A's 16-DOF mammal-like quadruped (`/work/shared/reference.md`),
//! identical at its defaults to `models/quad16.urdf` in every kinematic and
//! inertial number.
//!
//! # Structure
//! Torso (box, the floating base) and four identical legs in the order LF, RF,
//! RH, LH. Per leg, in q order: `hip_roll` (about x), `hip_pitch` (y), `knee`
//! (y), `ankle` (y). Link names `{leg}_hip` (massless, between roll and
//! pitch, as in the URDF), `{leg}_thigh`, `{leg}_shank`, `{leg}_foot`.
//!
//! Frames (all link frames parallel to the torso's at q = 0; x forward, y left,
//! z up): the hip frame sits at the mount `(±mount_x, ±mount_y, mount_z)`
//! (+x for front legs, +y for left legs); the thigh frame coincides with it;
//! the knee is `thigh.length_m` below the thigh frame, the ankle
//! `shank.length_m` below the knee. Each cylinder hangs below its joint with its
//! CoM at mid-length; the foot sphere's centre (and CoM) is `foot.radius_m`
//! below the ankle, and the foot contact point (`foot_points`) is the bottom of
//! the sphere, `2 · foot.radius_m` below the ankle in the foot frame.
//!
//! # Inertia
//! Every inertia is the solid-shape formula of [`crate::description::Shape::solid_inertia`]
//! (box, solid cylinder about its axis z, solid sphere) for the part's mass and
//! current size, so a change of size keeps shape and inertia consistent. A mass
//! that is not overridden follows its part's volume at the study's density (a
//! thigh twice as long weighs twice as much); an overridden mass is taken as
//! given and the density follows.
//!
//! # Parameters
//! | path | default | unit | meaning |
//! |---|---|---|---|
//! | `torso.size_x_m` | 0.6 | m | torso box length (x) |
//! | `torso.size_y_m` | 0.3 | m | torso box width (y) |
//! | `torso.size_z_m` | 0.1 | m | torso box height (z) |
//! | `torso.mass_kg` | 10 | kg | torso mass (follows the box volume unless given) |
//! | `mount.x_m` | 0.25 | m | hip mount distance ahead of / behind the torso centre |
//! | `mount.y_m` | 0.15 | m | hip mount distance left / right of the torso centre |
//! | `mount.z_m` | 0 | m | hip mount height above the torso centre |
//! | `thigh.length_m` | 0.3 | m | hip to knee; thigh cylinder length |
//! | `thigh.radius_m` | 0.05 | m | thigh cylinder radius |
//! | `thigh.mass_kg` | 2.5 | kg | thigh mass (follows the cylinder volume unless given) |
//! | `shank.length_m` | 0.25 | m | knee to ankle; shank cylinder length |
//! | `shank.radius_m` | 0.04 | m | shank cylinder radius |
//! | `shank.mass_kg` | 1.5 | kg | shank mass (follows the cylinder volume unless given) |
//! | `foot.radius_m` | 0.03 | m | foot sphere radius (centre one radius below the ankle) |
//! | `foot.mass_kg` | 0.5 | kg | foot mass (follows the sphere volume unless given) |
//! | `joint.limit_rad` | 3.14159 | rad | symmetric position limit of every joint (the URDF's) |
//! | `actuator.effort_limit_nm` | 100 | N·m | torque limit of every joint (ASSUMPTION) |
//! | `actuator.velocity_limit_rad_s` | 30 | rad/s | speed limit of every joint (ASSUMPTION) |
//!
//! # Actuator assumptions
//! Study A gives no actuator data (the URDF's 1000 N·m / 100 rad/s are
//! placeholders). 100 N·m covers the static standing load with a wide margin
//! (a leg carries 28 kg · 9.81 / 4 ≈ 69 N at a lever of a few cm, i.e. a few
//! N·m) and the VMC's transients. 30 rad/s: lifting the foot the study's
//! 170 mm within half of a 0.15 s swing flexes the knee by about 1 rad, about
//! 14 rad/s on average and 21 rad/s at the peak of a sinusoidal profile; 30 rad/s
//! leaves a margin above that.

use super::links::{box_torso, solid_link};
use super::params::{Domain, ParamSpec, Values};
use crate::actuator_model::{ActuatorDefaults, ActuatorKind, MotorGear, ServoParams};
use crate::description::{JointDesc, JointKind, LinkDesc, RobotDescription, Shape};
use crate::sensors::{ONE_G_MPS2, SensorSpec};
use crate::spatial::Transform;
use glam::{DMat3, DVec3};

/// Robot name.
pub const NAME: &str = "quad16";

/// Legs in q order, with the signs of their mount offsets (x, y).
pub const LEGS: [(&str, f64, f64); 4] = [
    ("LF", 1.0, 1.0),
    ("RF", 1.0, -1.0),
    ("RH", -1.0, -1.0),
    ("LH", -1.0, 1.0),
];

/// Standing joint angles per leg `[hip_roll, hip_pitch, knee, ankle]` (rad): the
/// oracle's `stand_static` state. The thigh leans 0.3 rad back, the shank 0.3
/// rad forward, the foot is level, so the foot lands 5 cm · sin 0.3 ≈ 15 mm
/// behind the hip.
pub const STANCE_LEG_RAD: [f64; 4] = [0.0, 0.3, -0.6, 0.3];

/// Degrees to radians.
const DEG: f64 = std::f64::consts::PI / 180.0;

/// The mass (kg) [`SENSORS`]' foot sensors are chosen for: quad16's at its
/// defaults. A robot that is not built in gets them times its mass over this
/// (`robots::default_sensors`).
pub const SENSOR_REFERENCE_MASS_KG: f64 = 28.0;

/// quad16's sensors (`docs/sensors.md`), as on a 28 kg research quadruped: a
/// Bosch BMI088-class IMU (±24 g, ±2000 °/s, 16 bit; noise densities
/// 175 µg/√Hz and 0.014 °/s/√Hz), 14-bit absolute joint encoders with
/// velocity by differencing (2 ms filter), foot force sensing with 20/10 N
/// thresholds and 2 N noise.
pub const SENSORS: SensorSpec = SensorSpec {
    accel_noise_density: 175e-6 * ONE_G_MPS2,
    gyro_noise_density: 0.014 * DEG,
    accel_range_mps2: 24.0 * ONE_G_MPS2,
    gyro_range_radps: 2000.0 * DEG,
    encoder_resolution_rad: std::f64::consts::TAU / 16384.0,
    encoder_noise_std_rad: 1e-4,
    encoder_velocity_filter_s: 0.002,
    contact_on_threshold_n: 20.0,
    contact_off_threshold_n: 10.0,
    contact_noise_std_n: 2.0,
    contact_force_output: true,
};

/// quad16's actuators (`docs/actuators.md`): DC motors by default, N = 10
/// with a 1·10⁻⁴ kg·m² rotor (reflected 0.01 kg·m²), 0.1 N·m·s/rad viscous
/// and 0.5 N·m Coulomb friction, 100 Hz torque bandwidth, no latency; each
/// stalls at its joint's effort limit and runs free at its velocity limit /
/// 0.75 (100 N·m, 40 rad/s unless the `actuator.*` parameters change the
/// limits). Servo: the same motor under a 1 kHz PD of 300 N·m/rad and
/// 5 N·m·s/rad. quad16 walks at least as well on its motors as on ideal
/// sources (`docs/actuators.md`, "Defaults").
pub const ACTUATORS: ActuatorDefaults = ActuatorDefaults {
    kind: ActuatorKind::DcMotor,
    gear: MotorGear {
        gear_ratio: 10.0,
        rotor_inertia_kgm2: 1e-4,
        viscous_nms_per_rad: 0.1,
        coulomb_nm: 0.5,
        bandwidth_hz: 100.0,
        latency_ticks: 0,
    },
    servo_rating: None,
    servo: ServoParams {
        kp_nm_per_rad: 300.0,
        kd_nms_per_rad: 5.0,
        rate_hz: 1000.0,
    },
};

/// The parameter table (see the module docs).
#[expect(
    clippy::approx_constant,
    reason = "the URDF's ±3.14159 joint range, kept so the built-in equals the URDF"
)]
pub const PARAMS: &[ParamSpec] = &[
    ParamSpec::new(
        "torso.size_x_m",
        0.6,
        "m",
        "torso box length (x)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "torso.size_y_m",
        0.3,
        "m",
        "torso box width (y)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "torso.size_z_m",
        0.1,
        "m",
        "torso box height (z)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "torso.mass_kg",
        10.0,
        "kg",
        "torso mass (follows the box volume unless given)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "mount.x_m",
        0.25,
        "m",
        "hip mount distance ahead of / behind the torso centre",
        Domain::Finite,
    ),
    ParamSpec::new(
        "mount.y_m",
        0.15,
        "m",
        "hip mount distance left / right of the torso centre",
        Domain::Finite,
    ),
    ParamSpec::new(
        "mount.z_m",
        0.0,
        "m",
        "hip mount height above the torso centre",
        Domain::Finite,
    ),
    ParamSpec::new(
        "thigh.length_m",
        0.3,
        "m",
        "hip to knee; thigh cylinder length",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "thigh.radius_m",
        0.05,
        "m",
        "thigh cylinder radius",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "thigh.mass_kg",
        2.5,
        "kg",
        "thigh mass (follows the cylinder volume unless given)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "shank.length_m",
        0.25,
        "m",
        "knee to ankle; shank cylinder length",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "shank.radius_m",
        0.04,
        "m",
        "shank cylinder radius",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "shank.mass_kg",
        1.5,
        "kg",
        "shank mass (follows the cylinder volume unless given)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "foot.radius_m",
        0.03,
        "m",
        "foot sphere radius (centre one radius below the ankle)",
        Domain::NonNegative,
    ),
    ParamSpec::new(
        "foot.mass_kg",
        0.5,
        "kg",
        "foot mass (follows the sphere volume unless given)",
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
        100.0,
        "N·m",
        "torque limit of every joint (ASSUMPTION: the study gives none)",
        Domain::Positive,
    ),
    ParamSpec::new(
        "actuator.velocity_limit_rad_s",
        30.0,
        "rad/s",
        "speed limit of every joint (ASSUMPTION: the study gives none)",
        Domain::Positive,
    ),
];

/// Builds the description from resolved parameters.
pub(crate) fn build(p: &Values) -> RobotDescription {
    let (thigh_l, thigh_r) = (p.get("thigh.length_m"), p.get("thigh.radius_m"));
    let thigh_mass = p.mass_following(
        "thigh.mass_kg",
        p.ratio("thigh.length_m") * p.ratio("thigh.radius_m").powi(2),
    );
    let (shank_l, shank_r) = (p.get("shank.length_m"), p.get("shank.radius_m"));
    let shank_mass = p.mass_following(
        "shank.mass_kg",
        p.ratio("shank.length_m") * p.ratio("shank.radius_m").powi(2),
    );
    let foot_r = p.get("foot.radius_m");
    let foot_mass = p.mass_following("foot.mass_kg", p.ratio("foot.radius_m").powi(3));
    let mount = DVec3::new(p.get("mount.x_m"), p.get("mount.y_m"), p.get("mount.z_m"));
    let limit = p.get("joint.limit_rad");
    let effort = p.get("actuator.effort_limit_nm");
    let velocity = p.get("actuator.velocity_limit_rad_s");

    let mut d = RobotDescription::new(NAME);
    d.links.push(box_torso(p));
    let joint = |name: String, axis: DVec3, parent: &str, child: &str, at: DVec3| JointDesc {
        limits: Some((-limit, limit)),
        effort_limit: effort,
        velocity_limit: velocity,
        ..JointDesc::new(
            name,
            JointKind::Revolute { axis },
            parent,
            child,
            Transform::from_translation(at),
        )
    };
    for (leg, sx, sy) in LEGS {
        let hip = format!("{leg}_hip");
        let thigh = format!("{leg}_thigh");
        let shank = format!("{leg}_shank");
        let foot = format!("{leg}_foot");
        let mut hip_link = LinkDesc::new(hip.clone());
        hip_link.inertia_kgm2 = Some(DMat3::ZERO);
        d.links.push(hip_link);
        d.links.push(solid_link(
            thigh.clone(),
            thigh_mass,
            Shape::Cylinder {
                radius_m: thigh_r,
                length_m: thigh_l,
            },
            DVec3::new(0.0, 0.0, -0.5 * thigh_l),
        ));
        d.links.push(solid_link(
            shank.clone(),
            shank_mass,
            Shape::Cylinder {
                radius_m: shank_r,
                length_m: shank_l,
            },
            DVec3::new(0.0, 0.0, -0.5 * shank_l),
        ));
        d.links.push(solid_link(
            foot.clone(),
            foot_mass,
            Shape::Sphere { radius_m: foot_r },
            DVec3::new(0.0, 0.0, -foot_r),
        ));
        let at_mount = DVec3::new(sx * mount.x, sy * mount.y, mount.z);
        d.joints.push(joint(
            format!("{leg}_hip_roll"),
            DVec3::X,
            "torso",
            &hip,
            at_mount,
        ));
        d.joints.push(joint(
            format!("{leg}_hip_pitch"),
            DVec3::Y,
            &hip,
            &thigh,
            DVec3::ZERO,
        ));
        d.joints.push(joint(
            format!("{leg}_knee"),
            DVec3::Y,
            &thigh,
            &shank,
            DVec3::new(0.0, 0.0, -thigh_l),
        ));
        d.joints.push(joint(
            format!("{leg}_ankle"),
            DVec3::Y,
            &shank,
            &foot,
            DVec3::new(0.0, 0.0, -shank_l),
        ));
        d.feet.push(foot.clone());
        d.foot_points
            .push((foot, DVec3::new(0.0, 0.0, -2.0 * foot_r)));
    }
    d
}
