//! Contact dynamics against closed forms, with the engine's own dynamics (a
//! free body compiled by `Model::from_description`, ABA) and integrator
//! (RK4 via `integrate::step`, contact forces re-evaluated at every stage,
//! `update_after_step` once per step).

use glam::{DMat3, DQuat, DVec2, DVec3};
use quadsim_engine::contact::{
    self, ContactForces, ContactKind, ContactPoint, ContactState, GroundMaterial, GroundPreset,
    NormalLaw,
};
use quadsim_engine::description::{RobotBuilder, Shape};
use quadsim_engine::integrate::{Integrator, State, StepWorkspace, step};
use quadsim_engine::kinematics::forward_kinematics;
use quadsim_engine::spatial::Transform;
use quadsim_engine::terrain::{
    BoxObstacles, BoxSpec, HeightField, Incline, NoiseKind, Rough, StairDirection, Stairs,
    SteppingStones, TerrainPatch, TerrainShape, TerrainUnion, Trench,
};
use quadsim_engine::{BaseKind, Data, Model};

#[path = "common/counting_alloc.rs"]
mod counting_alloc;
use counting_alloc::allocations_in;

const G: f64 = 9.81;

/// A free body of `mass_kg` with the given inertia and contact points.
struct Sim {
    model: Model,
    data: Data,
    ws: StepWorkspace,
    state: State,
    points: Vec<ContactPoint>,
    states: Vec<ContactState>,
    terrain: TerrainUnion,
    zeros: Vec<f64>,
}

impl Sim {
    fn new(mass_kg: f64, inertia: DMat3, points: Vec<ContactPoint>, terrain: TerrainUnion) -> Sim {
        let desc = RobotBuilder::new("body")
            .link("body")
            .mass(mass_kg)
            .inertia(inertia)
            .done()
            .build();
        let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
        contact::ContactPoint::validate(&points, &model).unwrap();
        let data = Data::new(&model);
        let ws = StepWorkspace::new(&model);
        let state = State::neutral(&model);
        let zeros = vec![0.0; model.nv];
        let states = vec![ContactState::default(); points.len()];
        Sim {
            model,
            data,
            ws,
            state,
            points,
            states,
            terrain,
            zeros,
        }
    }

    fn sphere(mass_kg: f64, radius_m: f64, terrain: TerrainUnion) -> Sim {
        let i = Shape::Sphere { radius_m }.solid_inertia(mass_kg).unwrap();
        let p = ContactPoint::new(0, DVec3::ZERO, radius_m, ContactKind::Foot);
        Sim::new(mass_kg, i, vec![p], terrain)
    }

    fn set_pose(&mut self, pos: DVec3, rot: DQuat) {
        self.state.q[..7].copy_from_slice(&[pos.x, pos.y, pos.z, rot.x, rot.y, rot.z, rot.w]);
    }

    /// Records touchdown anchors at the initial state.
    fn init_contacts(&mut self) {
        forward_kinematics(&self.model, &mut self.data, &self.state.q, &self.state.v);
        contact::update_after_step(&self.points, &self.data, &self.terrain, &mut self.states);
    }

    fn step(&mut self, dt_s: f64) {
        let mut forces = ContactForces {
            terrain: &self.terrain,
            points: &self.points,
            states: &self.states,
        };
        step(
            &self.model,
            &mut self.data,
            &mut self.ws,
            &mut self.state,
            &self.zeros,
            dt_s,
            Integrator::Rk4,
            &mut forces,
        );
        forward_kinematics(&self.model, &mut self.data, &self.state.q, &self.state.v);
        contact::update_after_step(&self.points, &self.data, &self.terrain, &mut self.states);
    }

    fn pos(&self) -> DVec3 {
        DVec3::new(self.state.q[0], self.state.q[1], self.state.q[2])
    }

    /// Linear velocity of the base origin, world frame.
    fn vel(&self) -> DVec3 {
        let q = &self.state.q;
        DQuat::from_xyzw(q[3], q[4], q[5], q[6])
            * DVec3::new(self.state.v[0], self.state.v[1], self.state.v[2])
    }
}

fn ground(material: GroundMaterial) -> TerrainUnion {
    TerrainUnion::flat(0.0, material)
}

/// The materials of the equilibrium test: each preset with its linear law,
/// with Hunt–Crossley (n = 3/2) and with the hybrid law on both sides of δ₀,
/// and the closed-form static depth under `load`, written out here:
/// linear `m g / k`; Hunt–Crossley `(m g / k)^(1/n)`; hybrid `m g / k` when
/// that is ≤ δ₀, else `δ₀ + u` with `a u² + k u + k δ₀ − m g = 0`, `a = s k/δ₀`.
fn equilibrium_cases(load: f64, mass: f64) -> Vec<(String, GroundMaterial, f64)> {
    let mut out = Vec::new();
    for p in GroundPreset::ALL {
        let m = p.material();
        let (k, b) = (m.stiffness, m.damping);
        out.push((format!("{} linear", p.name()), m, load / k));
        // Hunt–Crossley with k in N/m^1.5; damping giving ζ ≈ 0.5 at equilibrium.
        let n = 1.5;
        let d_hc = (load / k).powf(1.0 / n);
        let k_lin = n * k * d_hc.powf(n - 1.0);
        let b_hc = (k_lin * mass).sqrt() / d_hc.powf(n);
        let hc = m
            .with_law(NormalLaw::HuntCrossley { exponent: n }, k, b_hc)
            .unwrap();
        out.push((format!("{} hunt-crossley", p.name()), hc, d_hc));
        // hybrid, equilibrium beyond δ₀ (stiffened) …
        let (d0, s) = (0.5 * load / k, 2.0);
        let a = s * k / d0;
        let u = (-k + (k * k - 4.0 * a * (k * d0 - load)).sqrt()) / (2.0 * a);
        let hy = m
            .with_law(
                NormalLaw::Hybrid {
                    depth0_m: d0,
                    stiffening: s,
                },
                k,
                b,
            )
            .unwrap();
        out.push((format!("{} hybrid stiff", p.name()), hy, d0 + u));
        // … and within the linear part
        let hy = m
            .with_law(
                NormalLaw::Hybrid {
                    depth0_m: 2.0 * load / k,
                    stiffening: s,
                },
                k,
                b,
            )
            .unwrap();
        out.push((format!("{} hybrid soft", p.name()), hy, load / k));
    }
    out
}

/// A 10 kg sphere released touching the ground settles at each law's static
/// depth within 1 %.
#[test]
fn dropped_sphere_settles_at_equilibrium() {
    let (mass, r) = (10.0, 0.05);
    for (name, material, expect) in equilibrium_cases(mass * G, mass) {
        let mut sim = Sim::sphere(mass, r, ground(material));
        sim.model.gravity = DVec3::new(0.0, 0.0, -G);
        sim.set_pose(DVec3::new(0.0, 0.0, r + 0.002), DQuat::IDENTITY);
        let dt = 2e-4;
        let mut mean = 0.0;
        let mut n = 0;
        for k in 0..15_000 {
            sim.step(dt);
            if k >= 14_000 {
                mean += r - sim.pos().z;
                n += 1;
            }
        }
        let depth = mean / n as f64;
        let rel = (depth - expect).abs() / expect;
        eprintln!("{name}: depth {depth:.6e} m, closed form {expect:.6e} m");
        assert!(
            rel < 0.01,
            "{name}: depth {depth:.6e} m vs {expect:.6e} m ({:.3} %)",
            rel * 100.0
        );
        let st = sim.states[0];
        assert!(
            st.in_contact && (st.normal_force_n - mass * G).abs() < 0.01 * mass * G,
            "{name}: {st:?}"
        );
    }
}

/// Coefficient of restitution of a linear spring–dashpot contact that cannot
/// pull (Schwager & Pöschel 2007, "Coefficient of restitution and
/// linear–dashpot model revisited", Granular Matter 9:465–469, eqs. for ε):
/// with `ω₀² = k/m`, `β = b/(2m)`, the contact ends when the force
/// `k ξ + b ξ̇` returns to zero, at `t_c`, not when `ξ` does, and
///
/// - `β < ω₀/√2`: `ε = exp(−(β/ω)(π − arctan(2βω/(ω² − β²))))`, `ω = √(ω₀² − β²)`;
/// - `ω₀/√2 ≤ β ≤ ω₀`: `ε = exp(−(β/ω) arctan(2βω/(β² − ω²)))`;
/// - `β > ω₀`: `ε = exp(−(β/Ω) ln((β + Ω)/(β − Ω)))`, `Ω = √(β² − ω₀²)`.
///
/// (Derivation: `ξ(t) = (v₀/ω) e^{−βt} sin ωt`; the force vanishes where
/// `ξ̈ = 0`, i.e. `tan ωt_c = −2βω/(ω² − β²)`, and there `ξ̇ = −v₀ e^{−βt_c}`.)
fn schwager_poschel(k: f64, b: f64, m: f64) -> f64 {
    let w0 = (k / m).sqrt();
    let beta = b / (2.0 * m);
    if beta < w0 / 2f64.sqrt() {
        let w = (w0 * w0 - beta * beta).sqrt();
        (-(beta / w) * (std::f64::consts::PI - (2.0 * beta * w / (w * w - beta * beta)).atan()))
            .exp()
    } else if beta <= w0 {
        let w = (w0 * w0 - beta * beta).sqrt();
        (-(beta / w) * (2.0 * beta * w / (beta * beta - w * w)).atan()).exp()
    } else {
        let om = (beta * beta - w0 * w0).sqrt();
        (-(beta / om) * ((beta + om) / (beta - om)).ln()).exp()
    }
}

/// Runs a zero-gravity impact of a 10 kg sphere at 1 m/s along `-normal`
/// starting at first touch; returns the rebound velocity (world).
fn impact(terrain: TerrainUnion, start: DVec3, normal: DVec3) -> DVec3 {
    let (mass, r) = (10.0, 0.05);
    let mut sim = Sim::sphere(mass, r, terrain);
    sim.model.gravity = DVec3::ZERO;
    sim.set_pose(start, DQuat::IDENTITY);
    sim.state.v[..3].copy_from_slice(&(-normal).to_array());
    let dt = 1e-5;
    let mut touched = false;
    for _ in 0..200_000 {
        sim.step(dt);
        touched |= sim.states[0].in_contact;
        if touched && !sim.states[0].in_contact {
            return sim.vel();
        }
    }
    panic!("the sphere never left the ground");
}

/// A sphere hitting the ground at 1 m/s in zero gravity rebounds with the
/// Schwager–Pöschel coefficient of restitution within 2 %, for every preset
/// (all underdamped, β/ω₀ from 0.22 to 0.5) and for custom materials in the
/// other two regimes (β/ω₀ = 0.85 and 1.5).
#[test]
fn restitution_matches_schwager_poschel() {
    let m = 10.0;
    let mut materials: Vec<(String, GroundMaterial)> = GroundPreset::ALL
        .iter()
        .map(|p| (p.name().to_string(), p.material()))
        .collect();
    for ratio in [0.85, 1.5] {
        let k: f64 = 2e4;
        let b = 2.0 * m * ratio * f64::sqrt(k / m);
        materials.push((
            format!("β/ω₀ = {ratio}"),
            GroundMaterial::custom(k, b, 0.5).unwrap(),
        ));
    }
    for (name, mat) in materials {
        let v = impact(ground(mat), DVec3::new(0.0, 0.0, 0.05), DVec3::Z);
        let expect = schwager_poschel(mat.stiffness, mat.damping, m);
        let eps = v.z;
        eprintln!("{name}: ε = {eps:.5}, Schwager–Pöschel {expect:.5}");
        assert!(
            (eps - expect).abs() / expect < 0.02,
            "{name}: ε = {eps:.5} vs Schwager–Pöschel {expect:.5}"
        );
        // the naive estimate exp(−βπ/ω), ending the contact at ξ = 0, is far off
        assert!(v.x.abs() < 1e-9 && v.y.abs() < 1e-9, "{name}: {v}");
    }
}

/// The same impact horizontally into a stair riser (normal −x): the rebound
/// is horizontal with the same coefficient, so the riser's contact normal and
/// depth drive the dynamics (a vertical 15 cm "depth" would launch it upward).
#[test]
fn riser_impact_is_horizontal() {
    let mat = GroundPreset::Concrete.material();
    let stairs = Stairs::new(StairDirection::Up, 0.15, 0.3, 3, 1.0, 0.3).unwrap();
    let t = TerrainUnion::new().with(TerrainPatch::at_origin(TerrainShape::Stairs(stairs), mat));
    // centre 0.1 m above the first tread, touching the second riser (x = 0.3)
    let v = impact(t, DVec3::new(0.3 - 0.05, 0.0, 0.25), -DVec3::X);
    let expect = schwager_poschel(mat.stiffness, mat.damping, 10.0);
    assert!(
        (-v.x - expect).abs() / expect < 0.02,
        "ε = {} vs {expect}",
        -v.x
    );
    assert!(v.z.abs() < 1e-9 && v.y.abs() < 1e-9, "{v}");
}

/// Mass (kg) of the flat box of the incline tests.
const BOX_MASS_KG: f64 = 10.0;

/// The flat 0.4 × 0.3 × 0.05 m box of the incline tests: its rotational
/// inertia about its centre at [`BOX_MASS_KG`], its half size (m), and
/// contact points of radius `radius_m` at its four bottom corners (body
/// frame at its centre).
fn flat_box(radius_m: f64, kind: ContactKind) -> (DMat3, DVec3, Vec<ContactPoint>) {
    let size = DVec3::new(0.4, 0.3, 0.05);
    let inertia = Shape::Box { size_m: size }
        .solid_inertia(BOX_MASS_KG)
        .unwrap();
    let h = 0.5 * size;
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
        .iter()
        .map(|&(sx, sy)| ContactPoint::new(0, DVec3::new(sx * h.x, sy * h.y, -h.z), radius_m, kind))
        .collect();
    (inertia, h, corners)
}

/// A flat 10 kg box on four corner contact points rests on an incline
/// `atan μ − 10°` and slides down `atan μ + 10°` with
/// `a = g (sin θ − μ cos θ)` within 2 % once the touchdown transient is over.
#[test]
fn box_on_incline_sticks_and_slides() {
    let mass = BOX_MASS_KG;
    let (inertia, h, corners) = flat_box(0.0, ContactKind::Torso);
    for p in GroundPreset::ALL {
        let mat = p.material();
        let mu = mat.friction;
        for (delta_deg, slides) in [(-10.0, false), (10.0, true)] {
            let theta = mu.atan() + f64::to_radians(delta_deg);
            let incline = Incline::new(theta, DVec2::INFINITY).unwrap();
            let terrain = TerrainUnion::new()
                .with(TerrainPatch::at_origin(TerrainShape::Incline(incline), mat));
            let mut sim = Sim::new(mass, inertia, corners.clone(), terrain);
            sim.model.gravity = DVec3::new(0.0, 0.0, -G);
            // box axes on the slope (z along the normal), resting at its static depth
            let rot = DQuat::from_rotation_y(-theta);
            let n = rot * DVec3::Z;
            let sink = mass * G * theta.cos() / (4.0 * mat.stiffness);
            sim.set_pose(n * (h.z - sink), rot);
            sim.init_contacts();
            let dt = 1e-4;
            let downhill = -(rot * DVec3::X);
            let (t1, t2) = (0.5, 1.5);
            let (mut v1, mut x1) = (0.0, 0.0);
            let mut t = 0.0;
            while t < t2 - 0.5 * dt {
                sim.step(dt);
                t += dt;
                if (t - t1).abs() < 0.5 * dt {
                    v1 = sim.vel().dot(downhill);
                    x1 = sim.pos().dot(downhill);
                }
            }
            let v2 = sim.vel().dot(downhill);
            let x2 = sim.pos().dot(downhill);
            let name = format!("{} θ = {:.2}°", p.name(), theta.to_degrees());
            eprintln!("{name}: v {v1:.5} → {v2:.5} m/s, x {x1:.3e} → {x2:.3e} m");
            if slides {
                let a = (v2 - v1) / (t2 - t1);
                let expect = G * (theta.sin() - mu * theta.cos());
                assert!(
                    (a - expect).abs() / expect < 0.02,
                    "{name}: a = {a:.4} vs {expect:.4} m/s²"
                );
                assert!(
                    sim.states.iter().all(|s| s.in_contact && s.slipping),
                    "{name}: {:?}",
                    sim.states
                );
            } else {
                assert!(v2.abs() < 1e-4, "{name}: still moving at {v2} m/s");
                assert!((x2 - x1).abs() < 1e-5, "{name}: crept {} m", x2 - x1);
                assert!(x2.abs() < 1e-3, "{name}: moved {x2} m");
                assert!(
                    sim.states.iter().all(|s| s.in_contact && !s.slipping),
                    "{name}: {:?}",
                    sim.states
                );
            }
        }
    }
}

/// The Hunt–Crossley ground of issue 29 item 6: k 2e6 N/m^1.5, b 9e5
/// N·s/m^2.5, μ 0.5, exponent 1.5.
fn hunt_crossley_ground() -> GroundMaterial {
    let (k, b) = (2e6, 9e5);
    GroundMaterial::custom(k, b, 0.5)
        .unwrap()
        .with_law(NormalLaw::HuntCrossley { exponent: 1.5 }, k, b)
        .unwrap()
}

/// How far (m, along the slope, downhill) the flat box of
/// [`box_on_incline_sticks_and_slides`] moves on a 20° incline of `mat`
/// in 2 s from rest at its static depth, stepped at `dt` with RK4, and how
/// far in the last second; with the contacts' states at the end.
fn box_creep_on_20_degrees(mat: GroundMaterial, dt: f64) -> (f64, f64, Vec<ContactState>) {
    let mass = BOX_MASS_KG;
    let (inertia, h, corners) = flat_box(0.0, ContactKind::Torso);
    let theta = 20f64.to_radians();
    let incline = Incline::new(theta, DVec2::INFINITY).unwrap();
    let terrain =
        TerrainUnion::new().with(TerrainPatch::at_origin(TerrainShape::Incline(incline), mat));
    let mut sim = Sim::new(mass, inertia, corners, terrain);
    sim.model.gravity = DVec3::new(0.0, 0.0, -G);
    let rot = DQuat::from_rotation_y(-theta);
    let n = rot * DVec3::Z;
    let sink = mat
        .law
        .static_depth(mat.stiffness, mass * G * theta.cos() / 4.0);
    sim.set_pose(n * (h.z - sink), rot);
    sim.init_contacts();
    let downhill = -(rot * DVec3::X);
    let x0 = sim.pos().dot(downhill);
    let steps = (2.0 / dt).round() as usize;
    let mut x1 = x0;
    for k in 1..=steps {
        sim.step(dt);
        if k == steps / 2 {
            x1 = sim.pos().dot(downhill);
        }
    }
    let x2 = sim.pos().dot(downhill);
    (x2 - x0, x2 - x1, sim.states.clone())
}

/// Inside the friction cone a Hunt–Crossley ground holds: the 10 kg box on
/// a 20° incline (tan 20° = 0.36 < μ = 0.5) moves less than 1 mm in 2 s,
/// at the scenarios' dt = 0.5 ms and at 0.1 ms. It crept 32 mm when the
/// tangential gains were the normal law's numbers (issue 29, item 6). The
/// 1 mm bound is what sticking allows: each corner's anchor spring
/// deflects by its shear over `k_t` (m g sin θ / 4 / k_t ≈ 0.09 mm) plus the
/// touchdown transient from the static depth; no creep goes on in the last
/// second (< 10 µm), and every corner sticks at the end.
#[test]
fn hunt_crossley_ground_holds_a_box_inside_the_friction_cone() {
    let mat = hunt_crossley_ground();
    for dt in [5e-4, 1e-4] {
        let (moved, last_second, states) = box_creep_on_20_degrees(mat, dt);
        eprintln!("dt {dt}: moved {moved:.3e} m, {last_second:.3e} m in the last second");
        assert!(moved.abs() < 1e-3, "dt {dt}: moved {moved} m in 2 s");
        assert!(
            last_second.abs() < 1e-5,
            "dt {dt}: crept {last_second} m in the last second"
        );
        assert!(
            states.iter().all(|s| s.in_contact && !s.slipping),
            "dt {dt}: {states:?}"
        );
    }
}

/// The force [`contact::update_after_step`] keeps for the next evaluation
/// at the same kinematics is, bit for bit, what a fresh evaluation finds
/// there against the moved anchors: a tilted box dropped with a sideways
/// velocity onto an incline goes through lift-off, touchdown, sticking and
/// slipping, and at every step `contact_forces` from the kept force and from
/// the states without their caches (querying the terrain, evaluating the
/// laws) add the same `f_ext`. Away from those kinematics the kept force is
/// not used.
/// `states` with neither the kept terrain query nor the kept force: what a
/// first evaluation sees.
fn without_caches(states: &[ContactState]) -> Vec<ContactState> {
    states
        .iter()
        .map(|s| ContactState {
            last_query: None,
            last_force: None,
            ..*s
        })
        .collect()
}

#[test]
fn kept_force_is_the_fresh_evaluation() {
    let mass = BOX_MASS_KG;
    let (inertia, _, corners) = flat_box(0.01, ContactKind::Foot);
    let mat = GroundPreset::Grass.material();
    let incline = Incline::new(0.2, DVec2::INFINITY).unwrap();
    let terrain =
        TerrainUnion::new().with(TerrainPatch::at_origin(TerrainShape::Incline(incline), mat));
    let mut sim = Sim::new(mass, inertia, corners, terrain);
    sim.model.gravity = DVec3::new(0.0, 0.0, -G);
    sim.set_pose(DVec3::new(0.0, 0.0, 0.08), DQuat::from_rotation_x(0.3));
    sim.state.v[1] = 0.8;
    sim.init_contacts();
    let fresh = |sim: &Sim, states: &[ContactState]| {
        let mut d = sim.data.clone();
        d.clear_external_forces();
        contact::contact_forces(&sim.points, &sim.model, &mut d, &sim.terrain, states, None);
        d.external_forces()[0]
    };
    let bits =
        |f: quadsim_engine::spatial::Force| [f.lin, f.ang].map(|v| v.to_array().map(f64::to_bits));
    let (mut touched, mut slipped, mut kept) = (0, 0, 0);
    for _ in 0..4000 {
        forward_kinematics(&sim.model, &mut sim.data, &sim.state.q, &sim.state.v);
        contact::update_after_step(&sim.points, &sim.data, &sim.terrain, &mut sim.states);
        let cold = without_caches(&sim.states);
        let with_kept = fresh(&sim, &sim.states);
        assert_eq!(bits(with_kept), bits(fresh(&sim, &cold)));
        touched += sim.states.iter().filter(|s| s.in_contact).count();
        slipped += sim.states.iter().filter(|s| s.slipping).count();
        kept += sim.states.iter().filter(|s| s.last_force.is_some()).count();
        let mut forces = ContactForces {
            terrain: &sim.terrain,
            points: &sim.points,
            states: &sim.states,
        };
        step(
            &sim.model,
            &mut sim.data,
            &mut sim.ws,
            &mut sim.state,
            &sim.zeros,
            2e-4,
            Integrator::SemiImplicitEuler,
            &mut forces,
        );
    }
    assert!(
        touched > 0 && slipped > 0 && kept == 4 * 4000,
        "{touched} {slipped} {kept}"
    );
    // at other kinematics the kept force is not used
    let states = sim.states.clone();
    sim.state.v[0] += 1.0;
    forward_kinematics(&sim.model, &mut sim.data, &sim.state.q, &sim.state.v);
    let cold = without_caches(&states);
    assert_eq!(bits(fresh(&sim, &states)), bits(fresh(&sim, &cold)));
}

/// Feet of a description: the foot link's collision sphere gives the contact
/// sphere, in the body the foot is merged into.
#[test]
fn feet_from_description_use_the_foot_sphere() {
    let desc = RobotBuilder::new("leg")
        .link("base")
        .mass(1.0)
        .inertia(DMat3::IDENTITY * 0.01)
        .done()
        .link("foot")
        .mass(0.1)
        .shape(
            Transform::from_translation(DVec3::new(0.0, 0.0, -0.03)),
            Shape::Sphere { radius_m: 0.03 },
        )
        .done()
        .fixed(
            "ankle",
            "base",
            "foot",
            Transform::from_translation(DVec3::new(0.1, 0.0, -0.4)),
        )
        .feet(&["foot"])
        .build();
    let model = Model::from_description(&desc, BaseKind::Floating).unwrap();
    let feet = ContactPoint::feet(&model, &desc);
    assert_eq!(feet.len(), 1);
    assert_eq!(feet[0].body, 0);
    assert!((feet[0].point_in_body - DVec3::new(0.1, 0.0, -0.43)).length() < 1e-12);
    assert_eq!(feet[0].radius_m, 0.03);
    let bad = [ContactPoint::new(3, DVec3::ZERO, 0.01, ContactKind::Knee)];
    assert!(ContactPoint::validate(&bad, &model).is_err());
}

/// Contact stepping allocates nothing: a sphere rolling and bouncing across
/// a union of every kind of terrain (RK4 with contact forces at every stage,
/// `update_after_step` after each step) makes no allocation once set up.
#[test]
fn contact_steps_allocate_nothing() {
    let mat = GroundPreset::Sand.material();
    let at = |shape, x: f64| TerrainPatch::new(shape, DVec3::new(x, 0.0, 0.0), 0.3, mat).unwrap();
    let size = DVec2::splat(1.0);
    let terrain = TerrainUnion::flat(0.0, GroundPreset::Concrete.material())
        .with(at(
            TerrainShape::Stairs(Stairs::new(StairDirection::Up, 0.05, 0.2, 3, 1.0, 0.1).unwrap()),
            0.2,
        ))
        .with(at(
            TerrainShape::Trench(Trench::new(0.2, 0.1, size).unwrap()),
            1.5,
        ))
        .with(at(
            TerrainShape::HeightField(
                HeightField::from_fn(20, 20, DVec2::splat(0.05), |x, y| {
                    0.01 * (x * 9.0).sin() * y
                })
                .unwrap(),
            ),
            2.5,
        ))
        .with(at(
            TerrainShape::Rough(
                Rough::new(
                    NoiseKind::Perlin {
                        wavelength_m: 0.5,
                        octaves: 3,
                        persistence: 0.5,
                    },
                    0.01,
                    3,
                    size,
                )
                .unwrap(),
            ),
            3.5,
        ))
        .with(at(
            TerrainShape::SteppingStones(
                SteppingStones::new(4, 4, DVec2::splat(0.15), 0.05, 0.02, 0.5, 0.01, 2).unwrap(),
            ),
            4.5,
        ))
        .with(at(
            TerrainShape::Boxes(
                BoxObstacles::new(vec![BoxSpec {
                    centre_m: DVec3::new(0.0, 0.0, 0.02),
                    size_m: DVec3::splat(0.04),
                    yaw_rad: 0.7,
                }])
                .unwrap(),
            ),
            5.5,
        ));
    let mut sim = Sim::sphere(2.0, 0.05, terrain);
    sim.model.gravity = DVec3::new(0.0, 0.0, -G);
    sim.step(1e-4);
    let mut touched = [false; 7];
    // drop the sphere, moving sideways, onto each patch and the default ground
    let n = allocations_in(|| {
        for (k, x) in [-0.5, 0.45, 1.45, 2.5, 3.5, 4.5, 5.5]
            .into_iter()
            .enumerate()
        {
            sim.set_pose(DVec3::new(x, 0.02, 0.15), DQuat::IDENTITY);
            sim.state.v[..3].copy_from_slice(&[0.5, 0.2, -0.5]);
            sim.states.fill(ContactState::default());
            for _ in 0..3000 {
                sim.step(1e-4);
                touched[k] |= sim.states[0].in_contact;
            }
        }
    });
    assert_eq!(n, 0, "contact stepping allocated {n} times");
    // control: the counter does see allocations
    let control = allocations_in(|| drop(std::hint::black_box(Vec::<u8>::with_capacity(8))));
    assert_eq!(control, 1);
    assert!(touched.iter().all(|&t| t), "{touched:?}");
}
