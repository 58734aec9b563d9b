//! Normal-force laws of a foot against the ground.
//!
//! Every law maps the penetration depth `δ ≥ 0` (m) and its rate `δ̇` (m/s,
//! positive while sinking in) to a normal force `f_n` (N) that **never pulls**:
//! the result is clamped at zero, so a contact separates as soon as its force
//! reaches zero, even while `δ > 0` (Schwager & Pöschel 2007).

/// How the normal force grows with penetration. `k` and `b` are the ground
/// material's stiffness and damping ([`super::GroundMaterial`]); their units
/// depend on the law and are stated per variant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalLaw {
    /// Linear spring–damper (Kelvin–Voigt), study A's `f = k δ + b δ̇`;
    /// `k` in N/m, `b` in N·s/m.
    Linear,
    /// Hunt–Crossley `f = k δⁿ + b δⁿ δ̇` (Hunt & Crossley 1975): the damping
    /// vanishes with the depth, so the force is continuous at touchdown;
    /// `k` in N/mⁿ, `b` in N·s/mⁿ⁺¹.
    HuntCrossley {
        /// Exponent `n > 0` (3/2 for Hertzian sphere contact).
        exponent: f64,
    },
    /// Linear down to `δ₀`, stiffening quadratically beyond (a soft layer over
    /// a harder bed):
    ///
    /// ```text
    /// f_s(δ) = k δ                              δ ≤ δ₀
    /// f_s(δ) = k δ + s k (δ − δ₀)² / δ₀         δ > δ₀
    /// f      = f_s(δ) + b δ̇
    /// ```
    ///
    /// The added term and its slope vanish at `δ₀`, so `f_s` is C¹ there;
    /// the stiffness `f_s'(δ) = k (1 + 2 s (δ − δ₀)/δ₀)` grows linearly beyond
    /// `δ₀` and is `k (1 + 2 s)` at `2 δ₀`. `k` in N/m, `b` in N·s/m.
    Hybrid {
        /// Depth `δ₀ > 0` where the stiffening starts (m).
        depth0_m: f64,
        /// Dimensionless stiffening `s ≥ 0`.
        stiffening: f64,
    },
}

impl NormalLaw {
    /// Elastic part `f_s(δ)` (N) for `δ ≥ 0`.
    #[inline]
    pub fn spring_force(&self, k: f64, depth_m: f64) -> f64 {
        match *self {
            NormalLaw::Linear => k * depth_m,
            NormalLaw::HuntCrossley { exponent } => k * depth_m.powf(exponent),
            NormalLaw::Hybrid {
                depth0_m,
                stiffening,
            } => {
                let e = (depth_m - depth0_m).max(0.0);
                k * depth_m + stiffening * k * e * e / depth0_m
            }
        }
    }

    /// Normal force (N, ≥ 0) at depth `depth_m` (> 0) sinking at `depth_rate_mps`.
    #[inline]
    pub fn normal_force(&self, k: f64, b: f64, depth_m: f64, depth_rate_mps: f64) -> f64 {
        if depth_m <= 0.0 {
            return 0.0;
        }
        let f = match *self {
            NormalLaw::Linear => k * depth_m + b * depth_rate_mps,
            NormalLaw::HuntCrossley { exponent } => {
                depth_m.powf(exponent) * (k + b * depth_rate_mps)
            }
            NormalLaw::Hybrid { .. } => self.spring_force(k, depth_m) + b * depth_rate_mps,
        };
        f.max(0.0)
    }

    /// Tangent stiffness `d f_s / dδ` (N/m) at `depth_m`.
    pub fn stiffness_at(&self, k: f64, depth_m: f64) -> f64 {
        match *self {
            NormalLaw::Linear => k,
            NormalLaw::HuntCrossley { exponent } => {
                exponent * k * depth_m.max(0.0).powf(exponent - 1.0)
            }
            NormalLaw::Hybrid {
                depth0_m,
                stiffening,
            } => k * (1.0 + 2.0 * stiffening * (depth_m - depth0_m).max(0.0) / depth0_m),
        }
    }

    /// Static depth (m) at which the elastic force carries `load_n` (N ≥ 0):
    /// `load/k` (linear), `(load/k)^(1/n)` (Hunt–Crossley), and for the hybrid
    /// law `load/k` up to `δ₀`, beyond it the root of
    /// `a u² + k u + k δ₀ − load = 0`, `u = δ − δ₀`, `a = s k/δ₀`.
    pub fn static_depth(&self, k: f64, load_n: f64) -> f64 {
        match *self {
            NormalLaw::Linear => load_n / k,
            NormalLaw::HuntCrossley { exponent } => (load_n / k).powf(1.0 / exponent),
            NormalLaw::Hybrid {
                depth0_m,
                stiffening,
            } => {
                let lin = load_n / k;
                if lin <= depth0_m || stiffening == 0.0 {
                    return lin;
                }
                let a = stiffening * k / depth0_m;
                let c = k * depth0_m - load_n;
                // numerically stable root of a u² + k u + c = 0 with c < 0
                let u = -2.0 * c / (k + (k * k - 4.0 * a * c).sqrt());
                depth0_m + u
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The hybrid law is C¹ at δ₀: value and slope match from both sides.
    #[test]
    fn hybrid_is_c1_at_depth0() {
        let law = NormalLaw::Hybrid {
            depth0_m: 0.01,
            stiffening: 3.0,
        };
        let k = 2e4;
        let h = 1e-7;
        let below = (law.spring_force(k, 0.01) - law.spring_force(k, 0.01 - h)) / h;
        let above = (law.spring_force(k, 0.01 + h) - law.spring_force(k, 0.01)) / h;
        assert!((below - k).abs() / k < 1e-6, "{below}");
        assert!((above - k).abs() / k < 1e-3, "{above}");
        assert!((law.spring_force(k, 0.02) - k * 0.02 - 3.0 * k * 0.01).abs() < 1e-9);
    }

    /// `static_depth` inverts `spring_force` for every law.
    #[test]
    fn static_depth_inverts_spring() {
        let laws = [
            NormalLaw::Linear,
            NormalLaw::HuntCrossley { exponent: 1.5 },
            NormalLaw::Hybrid {
                depth0_m: 0.002,
                stiffening: 2.0,
            },
        ];
        for law in laws {
            for load in [1.0, 98.1, 500.0] {
                let d = law.static_depth(3e4, load);
                let f = law.spring_force(3e4, d);
                assert!(
                    (f - load).abs() < 1e-9 * load.max(1.0),
                    "{law:?} {load} {f}"
                );
            }
        }
    }

    /// The force never pulls, however fast the foot leaves the ground.
    #[test]
    fn never_pulls() {
        // linear: k δ + b δ̇ < 0 for δ̇ < −k δ / b = −0.1 m/s;
        // Hunt–Crossley: δⁿ (k + b δ̇) < 0 for δ̇ < −k / b = −100 m/s.
        let linear = NormalLaw::Linear;
        assert!(linear.normal_force(1e5, 1e3, 0.001, -0.09) > 0.0);
        assert_eq!(linear.normal_force(1e5, 1e3, 0.001, -0.11), 0.0);
        let hc = NormalLaw::HuntCrossley { exponent: 1.5 };
        assert!(hc.normal_force(1e5, 1e3, 0.001, -99.0) > 0.0);
        assert_eq!(hc.normal_force(1e5, 1e3, 0.001, -101.0), 0.0);
        for law in [linear, hc] {
            assert_eq!(law.normal_force(1e5, 1e3, -0.001, 10.0), 0.0);
        }
    }
}
