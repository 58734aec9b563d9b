//! Ground materials: study A's presets (concrete, grass, mud, sand) and custom ones.
//!
//! | preset | k_g (N/m) | b_g (N·s/m) | μ | law |
//! |---|---|---|---|---|
//! | concrete | 100000 | 1000 | 0.8 | linear |
//! | grass | 50000 | 500 | 0.6 | linear |
//! | mud | 20000 | 200 | 0.3 | linear |
//! | sand | 30000 | 300 | 0.4 | linear |
//!
//! **Tangential gains.** Study A models the foot contact as one spring–damper
//! "per direction" but gives only the vertical gains. The presets use
//! `k_t = k_g` (N/m): the `ν = 0` end of Mindlin's elastic ratio
//! `k_t/k_n = 2(1 − ν)/(2 − ν)` (0.82 at ν = 0.3), the stiffest choice, which
//! keeps the creep of a sticking foot (`μ f_n / k_t` at most) sub-millimetre;
//! and `b_t = b_g / 4` (N·s/m). The tangential spring acts on lighter modes
//! than the normal one: a foot rolling about its ankle moves its contact point
//! sideways with an effective mass of only `I_foot / r²` (0.18 kg for quad16's
//! foot, r = 6 cm), and an explicit integrator needs `b·dt/m < 1` there. With
//! `b_t = b_g` that is 2.9 on concrete at dt = 0.5 ms and quad16 creeps and
//! chatters while standing; with `b_g / 4` it is 0.7 (regression test
//! `quad16_stands_on_every_preset` in `tests/stand.rs`).
//!
//! **Hunt–Crossley grounds** (`f = k δⁿ + b δⁿ δ̇`) state `k` in N/mⁿ and `b`
//! in N·s/mⁿ⁺¹, so their numbers cannot serve as the tangential gains (N/m,
//! N·s/m). Copied, a ground of k 2e6, b 9e5 gave `b_t` = 2.25e5 N·s/m: a
//! foot moving at 0.1 mm/s met more than its friction limit, slipped, and a
//! body on a 20° incline with μ 0.5 crept 32 mm in 2 s (issue 29, item 6).
//! Their default tangential gains are the linear equivalents at the static
//! depth `δ_ref = (W/k)^(1/n)` under a nominal contact load
//! `W` = [`NOMINAL_CONTACT_LOAD_N`], by the presets' rule: `k_t` the law's
//! tangent stiffness `n k δ_refⁿ⁻¹` and `b_t` a quarter of its damping
//! coefficient `b δ_refⁿ` ([`GroundMaterial::default_tangential`]; about
//! 9.8e4 N/m and 7.9 N·s/m for that ground). A scenario sets them itself with
//! `tangential_stiffness_n_per_m` and `tangential_damping_ns_per_m`.

use crate::contact::error::ContactError;
use crate::contact::law::NormalLaw;

/// The contact load (N) at which a Hunt–Crossley ground's default
/// tangential gains are taken: quad16's weight (28 kg) shared by its four
/// feet, about 69 N.
pub const NOMINAL_CONTACT_LOAD_N: f64 = 70.0;

/// One of study A's ground types.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum GroundPreset {
    /// Flat concrete: k 100000 N/m, b 1000 N·s/m, μ 0.8.
    Concrete,
    /// Uneven grass: k 50000 N/m, b 500 N·s/m, μ 0.6.
    Grass,
    /// Soft mud: k 20000 N/m, b 200 N·s/m, μ 0.3.
    Mud,
    /// Loose sand: k 30000 N/m, b 300 N·s/m, μ 0.4.
    Sand,
}

impl GroundPreset {
    /// All presets, in study A's table order.
    pub const ALL: [GroundPreset; 4] = [
        GroundPreset::Concrete,
        GroundPreset::Grass,
        GroundPreset::Mud,
        GroundPreset::Sand,
    ];

    /// Lower-case name as written in scenarios.
    pub fn name(self) -> &'static str {
        match self {
            GroundPreset::Concrete => "concrete",
            GroundPreset::Grass => "grass",
            GroundPreset::Mud => "mud",
            GroundPreset::Sand => "sand",
        }
    }

    /// The preset called `name` (case-insensitive).
    pub fn from_name(name: &str) -> Result<GroundPreset, ContactError> {
        GroundPreset::ALL
            .into_iter()
            .find(|p| p.name().eq_ignore_ascii_case(name))
            .ok_or_else(|| ContactError::UnknownPreset(name.to_owned()))
    }

    /// The preset's material (linear law; `k_t = k_g`, `b_t = b_g / 4`, see the module doc).
    pub fn material(self) -> GroundMaterial {
        let (k, b, mu) = match self {
            GroundPreset::Concrete => (100_000.0, 1000.0, 0.8),
            GroundPreset::Grass => (50_000.0, 500.0, 0.6),
            GroundPreset::Mud => (20_000.0, 200.0, 0.3),
            GroundPreset::Sand => (30_000.0, 300.0, 0.4),
        };
        GroundMaterial {
            preset: Some(self),
            law: NormalLaw::Linear,
            stiffness: k,
            damping: b,
            friction: mu,
            tangential_stiffness_npm: k,
            tangential_damping_nspm: b / 4.0,
        }
    }
}

/// The contact parameters of a ground surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GroundMaterial {
    /// The preset this material came from, `None` for a custom one (kept for reports).
    pub preset: Option<GroundPreset>,
    /// Normal-force law.
    pub law: NormalLaw,
    /// Normal stiffness `k_g` (N/m for linear and hybrid laws, N/mⁿ for Hunt–Crossley).
    pub stiffness: f64,
    /// Normal damping `b_g` (N·s/m; N·s/mⁿ⁺¹ for Hunt–Crossley).
    pub damping: f64,
    /// Coulomb friction coefficient μ (static = kinetic).
    pub friction: f64,
    /// Stiffness of the tangential anchor spring while sticking (N/m).
    pub tangential_stiffness_npm: f64,
    /// Tangential viscous damping while sticking (N·s/m).
    pub tangential_damping_nspm: f64,
}

impl Default for GroundMaterial {
    /// Concrete.
    fn default() -> Self {
        GroundPreset::Concrete.material()
    }
}

fn check(field: &'static str, value: f64, positive: bool) -> Result<(), ContactError> {
    let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(())
    } else {
        Err(ContactError::InvalidValue {
            field,
            value,
            why: if positive {
                "must be finite and > 0"
            } else {
                "must be finite and ≥ 0"
            },
        })
    }
}

impl GroundMaterial {
    /// A custom linear material with `k` (N/m), `b` (N·s/m) and μ; tangential
    /// gains `k_t = k`, `b_t = b / 4`, as for the presets.
    pub fn custom(k: f64, b: f64, mu: f64) -> Result<GroundMaterial, ContactError> {
        GroundMaterial {
            preset: None,
            law: NormalLaw::Linear,
            stiffness: k,
            damping: b,
            friction: mu,
            tangential_stiffness_npm: k,
            tangential_damping_nspm: b / 4.0,
        }
        .validated()
    }

    /// The preset called `name`.
    pub fn preset(name: &str) -> Result<GroundMaterial, ContactError> {
        Ok(GroundPreset::from_name(name)?.material())
    }

    /// This material with another normal law and normal gains (their units
    /// follow the law, see [`NormalLaw`]). The tangential gains are kept for
    /// the linear and hybrid laws (N/m and N·s/m like theirs); a
    /// Hunt–Crossley law gets [`Self::default_tangential`]'s, its own gains
    /// being in other units.
    pub fn with_law(
        mut self,
        law: NormalLaw,
        k: f64,
        b: f64,
    ) -> Result<GroundMaterial, ContactError> {
        self.law = law;
        self.stiffness = k;
        self.damping = b;
        self.preset = None;
        if let NormalLaw::HuntCrossley { .. } = law {
            // checked here: the gains below need k > 0
            check("stiffness", k, true)?;
            check("damping", b, false)?;
            (self.tangential_stiffness_npm, self.tangential_damping_nspm) =
                Self::default_tangential(law, k, b);
        }
        self.validated()
    }

    /// Default tangential gains (`k_t` N/m, `b_t` N·s/m) of a ground with
    /// normal `law`, `k` and `b`. Linear and hybrid laws: `k_t = k`,
    /// `b_t = b / 4` (the presets' rule, see the module doc). Hunt–Crossley:
    /// the law's tangent stiffness and a quarter of its damping coefficient
    /// at the static depth `δ_ref` under [`NOMINAL_CONTACT_LOAD_N`]:
    /// `k_t = n k δ_refⁿ⁻¹`, `b_t = b δ_refⁿ / 4`.
    pub fn default_tangential(law: NormalLaw, k: f64, b: f64) -> (f64, f64) {
        match law {
            NormalLaw::Linear | NormalLaw::Hybrid { .. } => (k, b / 4.0),
            NormalLaw::HuntCrossley { exponent } => {
                let depth = law.static_depth(k, NOMINAL_CONTACT_LOAD_N);
                (law.stiffness_at(k, depth), b * depth.powf(exponent) / 4.0)
            }
        }
    }

    /// This material with other tangential gains (N/m, N·s/m).
    pub fn with_tangential(mut self, k_t: f64, b_t: f64) -> Result<GroundMaterial, ContactError> {
        self.tangential_stiffness_npm = k_t;
        self.tangential_damping_nspm = b_t;
        self.validated()
    }

    /// Checks every field; the error names the first bad one.
    pub fn validated(self) -> Result<GroundMaterial, ContactError> {
        check("stiffness", self.stiffness, true)?;
        check("damping", self.damping, false)?;
        check("friction", self.friction, false)?;
        check(
            "tangential_stiffness_npm",
            self.tangential_stiffness_npm,
            true,
        )?;
        check(
            "tangential_damping_nspm",
            self.tangential_damping_nspm,
            false,
        )?;
        match self.law {
            NormalLaw::Linear => {}
            NormalLaw::HuntCrossley { exponent } => check("exponent", exponent, true)?,
            NormalLaw::Hybrid {
                depth0_m,
                stiffening,
            } => {
                check("depth0_m", depth0_m, true)?;
                check("stiffening", stiffening, false)?;
            }
        }
        Ok(self)
    }

    /// Display name: the preset's, or `custom`.
    pub fn name(&self) -> &'static str {
        self.preset.map_or("custom", GroundPreset::name)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hunt–Crossley grounds get tangential gains in N/m and N·s/m: the
    /// linear equivalents at the static depth under the nominal load (the
    /// tangential spring then carries that load's shear as stiffly as the
    /// normal spring carries the load); linear and hybrid grounds keep theirs.
    #[test]
    fn hunt_crossley_tangential_gains_are_in_their_own_units() {
        let (k, b, n) = (2e6, 9e5, 1.5);
        let law = NormalLaw::HuntCrossley { exponent: n };
        let m = GroundMaterial::custom(k, b, 0.5)
            .unwrap()
            .with_law(law, k, b)
            .unwrap();
        let depth = (NOMINAL_CONTACT_LOAD_N / k).powf(1.0 / n);
        let k_t = n * k * depth.powf(n - 1.0);
        assert!((m.tangential_stiffness_npm - k_t).abs() < 1e-9 * k_t);
        assert!((m.tangential_damping_nspm - b * depth.powf(n) / 4.0).abs() < 1e-9);
        // about 9.8e4 N/m (concrete's is 1e5) and 7.9 N·s/m, not 2e6 and 2.25e5
        assert!(
            (9.5e4..1.0e5).contains(&m.tangential_stiffness_npm),
            "{m:?}"
        );
        assert!((7.5..8.5).contains(&m.tangential_damping_nspm), "{m:?}");
        // linear and hybrid: unchanged (k, b / 4)
        let c = GroundMaterial::default();
        assert_eq!(
            (c.tangential_stiffness_npm, c.tangential_damping_nspm),
            (1e5, 250.0)
        );
        let h = c
            .with_law(
                NormalLaw::Hybrid {
                    depth0_m: 1e-3,
                    stiffening: 1.0,
                },
                5e4,
                100.0,
            )
            .unwrap();
        assert_eq!(
            (h.tangential_stiffness_npm, h.tangential_damping_nspm),
            (1e5, 250.0)
        );
        // a bad Hunt–Crossley stiffness is an error, not NaN gains
        assert!(matches!(
            c.with_law(law, 0.0, b),
            Err(ContactError::InvalidValue {
                field: "stiffness",
                ..
            })
        ));
    }

    #[test]
    fn presets_by_name_and_bad_input() {
        let sand = GroundMaterial::preset("Sand").unwrap();
        assert_eq!(sand.stiffness, 30_000.0);
        assert_eq!(sand.friction, 0.4);
        assert!(matches!(
            GroundMaterial::preset("ice"),
            Err(ContactError::UnknownPreset(n)) if n == "ice"
        ));
        assert!(matches!(
            GroundMaterial::custom(1e4, -1.0, 0.5),
            Err(ContactError::InvalidValue {
                field: "damping",
                ..
            })
        ));
        assert!(matches!(
            GroundMaterial::default().with_law(
                NormalLaw::Hybrid {
                    depth0_m: 0.0,
                    stiffening: 1.0
                },
                1e4,
                10.0
            ),
            Err(ContactError::InvalidValue {
                field: "depth0_m",
                ..
            })
        ));
    }
}
