//! Study B's leg kinematics in the study's own symbols: its printed forward
//! and inverse formulas, taken literally, and the corrected closed-form
//! inverse. `docs/study_b_kinematics.md` reports where the printed inverse
//! fails; `engine/tests/leg_ik.rs` asserts it.
//!
//! Symbols (`/work/shared/reference.md`): joint angles θ1 (hip yaw), θ2
//! (thigh), θ3 (knee); link lengths l1 (across the leg), l2 (thigh), l3
//! (shank); mount offsets a, b, c; foot position `p` in the body frame.
//! The study's frame has no mount yaw (quad12's built-in turns each leg
//! outward: see [`quadsim_engine::legs::Quad12Leg`]).

use glam::DVec3;
use quadsim_engine::legs::{IkError, KneeBranch, wrap_angle};

/// Study B's leg: mount offsets and link lengths (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StudyBLeg {
    /// Mount offset a (m, body x).
    pub a_m: f64,
    /// Mount offset b (m, body y).
    pub b_m: f64,
    /// Mount offset c (m, body z).
    pub c_m: f64,
    /// l1: hip-yaw to hip-pitch offset, across the leg (m).
    pub l1_m: f64,
    /// l2: thigh (m).
    pub l2_m: f64,
    /// l3: shank (m).
    pub l3_m: f64,
}

impl StudyBLeg {
    /// The study's lengths (50, 100, 80 mm) at quad12's left-front mount
    /// (a, b, c) = (150, 75, 0) mm.
    pub const STUDY: StudyBLeg = StudyBLeg {
        a_m: 0.15,
        b_m: 0.075,
        c_m: 0.0,
        l1_m: 0.05,
        l2_m: 0.1,
        l3_m: 0.08,
    };

    /// The printed forward kinematics:
    /// `p_x = c1 c23 l3 + c1 c2 l2 − l1 s1 + a`,
    /// `p_y = s1 c23 l3 + s1 c2 l2 + l1 c1 + b`,
    /// `p_z = −s23 l3 − s2 l2 + c`.
    pub fn fk(&self, t: [f64; 3]) -> DVec3 {
        let (s1, c1) = t[0].sin_cos();
        let (s2, c2) = t[1].sin_cos();
        let (s23, c23) = (t[1] + t[2]).sin_cos();
        let (l1, l2, l3) = (self.l1_m, self.l2_m, self.l3_m);
        DVec3::new(
            c1 * c23 * l3 + c1 * c2 * l2 - l1 * s1 + self.a_m,
            s1 * c23 * l3 + s1 * c2 * l2 + l1 * c1 + self.b_m,
            -s23 * l3 - s2 * l2 + self.c_m,
        )
    }

    /// The printed inverse, literally (single-argument `atan`, as printed):
    /// with `ρ = √((p_x−a)² + (p_y−b)²)`, `A = p_z − c`, `B = ρ − l1`,
    /// - `θ1 = atan((p_y−b)/(p_x−a)) − atan(l1/ρ)`,
    /// - `θ2 = atan(A/B) − atan(√(A² + B² + l2² − l3²) / (2 l2))`,
    /// - `θ3` = [`Self::printed_theta3`] at these θ1, θ2.
    ///
    /// Wrong almost everywhere (see the doc).
    pub fn printed_ik(&self, p: DVec3) -> [f64; 3] {
        let (u, v) = (p.x - self.a_m, p.y - self.b_m);
        let rho = u.hypot(v);
        let a = p.z - self.c_m;
        let b = rho - self.l1_m;
        let t1 = (v / u).atan() - (self.l1_m / rho).atan();
        let root = (a * a + b * b + self.l2_m * self.l2_m - self.l3_m * self.l3_m).sqrt();
        let t2 = (a / b).atan() - (root / (2.0 * self.l2_m)).atan();
        [t1, t2, self.printed_theta3(p, t1, t2)]
    }

    /// The printed θ3 given θ1 and θ2:
    /// `atan((c2 (c1 p_x + s1 p_y − c1 a − s1 b) − s2 (p_z − c) − l2) /
    ///       (s2 (c1 p_x + s1 p_y − c1 a − s1 b) + c2 (p_z − c)))`.
    pub fn printed_theta3(&self, p: DVec3, t1: f64, t2: f64) -> f64 {
        let (s1, c1) = t1.sin_cos();
        let (s2, c2) = t2.sin_cos();
        let reach = c1 * p.x + s1 * p.y - c1 * self.a_m - s1 * self.b_m;
        let a = p.z - self.c_m;
        ((c2 * reach - s2 * a - self.l2_m) / (s2 * reach + c2 * a)).atan()
    }

    /// The corrected closed-form inverse (see the doc for its derivation):
    /// with `u = p_x − a`, `v = p_y − b`, `A = p_z − c`, `ρ = √(u² + v²)`,
    /// `R = √(ρ² − l1²)` (the leg's reach in its own plane, not `ρ − l1`),
    /// - `θ1 = atan2(v, u) − atan2(l1, R)`,
    /// - `cos θ3 = (R² + A² − l2² − l3²) / (2 l2 l3)`, `θ3 = ±acos(…)` (+ is
    ///   the nominal stance's branch),
    /// - `θ2 = atan2(−A, R) − atan2(l3 sin θ3, l2 + l3 cos θ3)`.
    ///
    /// # Errors
    /// [`IkError::NonFinite`], [`IkError::InsideOffset`] (`ρ < l1`),
    /// [`IkError::OutOfReach`] (`√(R² + A²)` outside `[|l2 − l3|, l2 + l3]`).
    pub fn ik(&self, p: DVec3, knee: KneeBranch) -> Result<[f64; 3], IkError> {
        if !p.is_finite() {
            return Err(IkError::NonFinite { target_m: p });
        }
        let (l1, l2, l3) = (self.l1_m, self.l2_m, self.l3_m);
        let (u, v, a) = (p.x - self.a_m, p.y - self.b_m, p.z - self.c_m);
        let rho = u.hypot(v);
        if rho < l1 {
            return Err(IkError::InsideOffset {
                distance_m: rho,
                offset_m: l1,
            });
        }
        let r = ((rho - l1) * (rho + l1)).sqrt();
        let t1 = v.atan2(u) - l1.atan2(r);
        let dist = r.hypot(a);
        let c3 = (r * r + a * a - l2 * l2 - l3 * l3) / (2.0 * l2 * l3);
        if !(-1.0 - 1e-12..=1.0 + 1e-12).contains(&c3) {
            return Err(IkError::OutOfReach {
                distance_m: dist,
                min_reach_m: (l2 - l3).abs(),
                max_reach_m: l2 + l3,
            });
        }
        // the nominal branch bends the knee positively (quad12's stance)
        let sign = match knee {
            KneeBranch::Nominal | KneeBranch::Positive => 1.0,
            KneeBranch::Negative => -1.0,
        };
        let t3 = sign * c3.clamp(-1.0, 1.0).acos();
        let t2 = (-a).atan2(r) - (l3 * t3.sin()).atan2(l2 + l3 * t3.cos());
        Ok([wrap_angle(t1), wrap_angle(t2), wrap_angle(t3)])
    }
}
