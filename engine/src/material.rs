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

use crate::contact::error::ContactError;
use crate::contact::law::NormalLaw;

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
    /// follow the law, see [`NormalLaw`]); the tangential gains are kept.
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
        self.validated()
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
