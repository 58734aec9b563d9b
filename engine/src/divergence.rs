//! When a simulated robot has diverged: a state that is not finite, a speed
//! no legged robot reaches, or a contact point sunk deep into the ground.
//! A fixed-step simulation that has gone there does not come back, so a run
//! stops at the first one and names it.

use crate::model::Model;

/// Largest base or joint speed before a robot counts as diverged (m/s for
/// the floating base's linear velocity).
pub const DIVERGED_LINEAR_SPEED_MPS: f64 = 100.0;
/// See [`DIVERGED_LINEAR_SPEED_MPS`] (rad/s: the base's angular velocity
/// and every joint's velocity).
pub const DIVERGED_ANGULAR_SPEED_RADPS: f64 = 1000.0;
/// Deepest contact penetration before a robot counts as diverged (m).
pub const DIVERGED_PENETRATION_M: f64 = 0.2;

/// What diverged.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Divergence {
    /// `q[index]` is not finite.
    Position {
        /// Index in `q`.
        index: usize,
    },
    /// `v[index]` is not finite.
    Velocity {
        /// Index in `v`.
        index: usize,
    },
    /// `|v[index]|` is beyond `limit` (m/s or rad/s, see
    /// [`DIVERGED_LINEAR_SPEED_MPS`]).
    Speed {
        /// Index in `v`.
        index: usize,
        /// The velocity (m/s or rad/s).
        value: f64,
        /// The limit it passed.
        limit: f64,
    },
    /// Contact point `point` is deeper than [`DIVERGED_PENETRATION_M`].
    Penetration {
        /// Index of the contact point.
        point: usize,
        /// Its penetration (m).
        depth_m: f64,
    },
}

/// The first divergence of the state `(q, v)` of a robot of `model`, in
/// this order: a position not finite, a velocity not finite, a speed beyond
/// its limit (each by lowest index).
pub fn state_divergence(model: &Model, q: &[f64], v: &[f64]) -> Option<Divergence> {
    let linear = if model.is_floating() {
        3.min(v.len())
    } else {
        0
    };
    // The usual answer first, without branches: this runs after every
    // step for every robot. Every speed within the angular limit, and the
    // linear ones within theirs (the smaller), is each within its own: one
    // vectorised pass over `v` and three entries, not two passes with a
    // scalar tail each.
    const _: () = assert!(DIVERGED_LINEAR_SPEED_MPS <= DIVERGED_ANGULAR_SPEED_RADPS);
    if all_within(q, f64::MAX)
        && all_within(v, DIVERGED_ANGULAR_SPEED_RADPS)
        && all_within(&v[..linear], DIVERGED_LINEAR_SPEED_MPS)
    {
        return None;
    }
    if let Some(index) = q.iter().position(|x| !x.is_finite()) {
        return Some(Divergence::Position { index });
    }
    if let Some(index) = v.iter().position(|x| !x.is_finite()) {
        return Some(Divergence::Velocity { index });
    }
    v.iter().enumerate().find_map(|(index, &value)| {
        let (limit, _) = speed_limit(model, index);
        (value.abs() > limit).then_some(Divergence::Speed {
            index,
            value,
            limit,
        })
    })
}

/// The divergence limit of velocity coordinate `index` of `model` and its
/// unit: [`DIVERGED_LINEAR_SPEED_MPS`] for a floating base's linear
/// velocity (`v[0..3]`), [`DIVERGED_ANGULAR_SPEED_RADPS`] for every other.
pub fn speed_limit(model: &Model, index: usize) -> (f64, &'static str) {
    if model.is_floating() && index < 3 {
        (DIVERGED_LINEAR_SPEED_MPS, "m/s")
    } else {
        (DIVERGED_ANGULAR_SPEED_RADPS, "rad/s")
    }
}

/// Whether every `|x|` is at most `limit` (so finite: a NaN fails the
/// comparison), without a branch per number.
fn all_within(xs: &[f64], limit: f64) -> bool {
    xs.iter().fold(true, |all, x| all & (x.abs() <= limit))
}

/// The first contact point (by index) among `penetrations_m` deeper than
/// [`DIVERGED_PENETRATION_M`].
pub fn penetration_divergence(penetrations_m: impl IntoIterator<Item = f64>) -> Option<Divergence> {
    penetrations_m
        .into_iter()
        .enumerate()
        .find_map(|(point, depth_m)| {
            (depth_m > DIVERGED_PENETRATION_M).then_some(Divergence::Penetration { point, depth_m })
        })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::BaseKind;

    fn quad16() -> Model {
        Model::from_description(
            &crate::robots::builtin("quad16").unwrap(),
            BaseKind::Floating,
        )
        .unwrap()
    }

    #[test]
    fn a_state_at_rest_has_not_diverged() {
        let m = quad16();
        assert_eq!(state_divergence(&m, &m.neutral_q(), &vec![0.0; m.nv]), None);
    }

    #[test]
    fn each_kind_is_found_in_order() {
        let m = quad16();
        let (mut q, mut v) = (m.neutral_q(), vec![0.0; m.nv]);
        // base linear speed: the 100 m/s limit; a joint: 1000 rad/s
        v[1] = -100.5;
        v[9] = 999.0;
        assert_eq!(
            state_divergence(&m, &q, &v),
            Some(Divergence::Speed {
                index: 1,
                value: -100.5,
                limit: DIVERGED_LINEAR_SPEED_MPS
            })
        );
        v[1] = 0.0;
        assert_eq!(state_divergence(&m, &q, &v), None);
        v[4] = 1000.5;
        assert!(matches!(
            state_divergence(&m, &q, &v),
            Some(Divergence::Speed { index: 4, limit, .. }) if limit == DIVERGED_ANGULAR_SPEED_RADPS
        ));
        // a velocity that is not finite comes before any speed
        v[7] = f64::NAN;
        assert_eq!(
            state_divergence(&m, &q, &v),
            Some(Divergence::Velocity { index: 7 })
        );
        // and a position that is not finite before any velocity
        q[10] = f64::INFINITY;
        assert_eq!(
            state_divergence(&m, &q, &v),
            Some(Divergence::Position { index: 10 })
        );
    }

    #[test]
    fn the_first_deep_point_is_named() {
        assert_eq!(penetration_divergence([0.01, 0.2, 0.0]), None);
        assert_eq!(
            penetration_divergence([0.01, 0.25, 0.3]),
            Some(Divergence::Penetration {
                point: 1,
                depth_m: 0.25
            })
        );
    }
}
