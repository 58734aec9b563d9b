//! Forming a study's variants from its variations: a full grid, a cycle,
//! random samples, or a Latin hypercube.

use std::collections::BTreeMap;

use rand::seq::SliceRandom;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;
use toml::Value;

use crate::scenario::vary::Variation;
use crate::scenario::{Locator, ScenarioError};

/// `[sweep]`.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepSpec {
    /// `grid` (default: every combination), `cycle` (variant k takes value
    /// k mod len of each), `random` or `lhs` (Latin hypercube) samples.
    pub combine: Option<String>,
    /// Number of variants for `random`, `lhs` and `cycle` (cycle's default: the longest list).
    pub samples: Option<usize>,
    /// Seed of random and Latin-hypercube samples (default 0).
    pub seed: Option<u64>,
}

/// Most variants a study may form.
pub const MAX_VARIANTS: usize = 1_000_000;

/// The variants, in a fixed order (paths in alphabetical order; in a grid
/// the first varies slowest).
pub fn variants(
    loc: &Locator<'_>,
    spec: &SweepSpec,
    vary: &[(String, Variation)],
) -> Result<Vec<BTreeMap<String, Value>>, ScenarioError> {
    let combine = spec.combine.as_deref().unwrap_or("grid");
    let seed = spec.seed.unwrap_or(0);
    let need_samples = |what: &str| -> Result<usize, ScenarioError> {
        match spec.samples {
            Some(0) => Err(loc.at("sweep.samples", "must be at least 1")),
            Some(n) if n > MAX_VARIANTS => Err(loc.at(
                "sweep.samples",
                format!("{n} variants is more than the {MAX_VARIANTS} a study may form"),
            )),
            Some(n) => Ok(n),
            None => Err(loc.at(
                "sweep.samples",
                format!("combine = \"{what}\" needs `samples`, the number of variants"),
            )),
        }
    };
    let rows: Vec<BTreeMap<String, Value>> = match combine {
        "grid" => {
            let mut n = 1usize;
            for (p, v) in vary {
                let Some(c) = v.count() else {
                    return Err(loc.at(
                        &format!("vary.{}", crate::scenario::spans::path_key(p)),
                        format!(
                            "'{p}': random draws have no grid; use combine = \"random\" or \"lhs\" with `samples`"
                        ),
                    ));
                };
                n = n.saturating_mul(c);
            }
            if n > MAX_VARIANTS {
                return Err(loc.at(
                    "vary",
                    format!(
                        "the grid has {n} variants, more than the {MAX_VARIANTS} a study may form"
                    ),
                ));
            }
            if spec.samples.is_some() {
                return Err(loc.at(
                    "sweep.samples",
                    "a grid runs every combination; `samples` belongs to random, lhs or cycle",
                ));
            }
            (0..n)
                .map(|k| {
                    let mut rest = k;
                    let mut idx = vec![0; vary.len()];
                    for (d, (_, v)) in idx.iter_mut().zip(vary).rev() {
                        let c = v.count().expect("checked");
                        *d = rest % c;
                        rest /= c;
                    }
                    vary.iter()
                        .zip(idx)
                        .map(|((p, v), i)| (p.clone(), v.value(i, &mut rng(seed, k, p))))
                        .collect()
                })
                .collect()
        }
        "cycle" => {
            let longest = vary.iter().filter_map(|(_, v)| v.count()).max();
            let n = match (spec.samples, longest) {
                (Some(_), _) => need_samples("cycle")?,
                (None, Some(n)) => n,
                (None, None) => need_samples("cycle")?,
            };
            (0..n)
                .map(|k| {
                    vary.iter()
                        .map(|(p, v)| (p.clone(), v.value(k, &mut rng(seed, k, p))))
                        .collect()
                })
                .collect()
        }
        "random" => {
            let n = need_samples("random")?;
            (0..n)
                .map(|k| {
                    vary.iter()
                        .map(|(p, v)| {
                            let mut r = rng(seed, k, p);
                            let i = v.count().map_or(0, |c| r.random_range(0..c));
                            (p.clone(), v.value(i, &mut r))
                        })
                        .collect()
                })
                .collect()
        }
        "lhs" => {
            let n = need_samples("lhs")?;
            // Each path's range is cut into n strata; every stratum is used
            // exactly once, in a random order per path.
            let mut cols: Vec<Vec<Value>> = Vec::with_capacity(vary.len());
            for (p, v) in vary {
                let mut r =
                    ChaCha8Rng::seed_from_u64(crate::world::stream_seed(seed, &format!("lhs/{p}")));
                let mut strata: Vec<usize> = (0..n).collect();
                strata.shuffle(&mut r);
                let col = strata
                    .iter()
                    .map(|&s| {
                        let u = (s as f64 + r.random::<f64>()) / n as f64;
                        match v {
                            Variation::Uniform { lo, hi } => Value::Float(lo + (hi - lo) * u),
                            other => {
                                let c = other.count().expect("finite");
                                let i = ((u * c as f64) as usize).min(c - 1);
                                other.value(i, &mut r)
                            }
                        }
                    })
                    .collect();
                cols.push(col);
            }
            (0..n)
                .map(|k| {
                    vary.iter()
                        .zip(&cols)
                        .map(|((p, _), col)| (p.clone(), col[k].clone()))
                        .collect()
                })
                .collect()
        }
        other => {
            return Err(loc.at(
                "sweep.combine",
                format!("unknown combine '{other}': expected grid, cycle, random or lhs"),
            ));
        }
    };
    Ok(rows)
}

fn rng(seed: u64, k: usize, path: &str) -> ChaCha8Rng {
    crate::scenario::vary::draw_rng(seed, &format!("variant-{k}"), path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn loc() -> Locator<'static> {
        Locator {
            path: Path::new("s.toml"),
            src: "",
        }
    }

    #[test]
    fn latin_hypercube_uses_every_stratum_once_per_path() {
        let vary = vec![
            ("a".to_string(), Variation::Uniform { lo: 0.0, hi: 1.0 }),
            ("b".to_string(), Variation::Uniform { lo: 10.0, hi: 20.0 }),
        ];
        let spec = SweepSpec {
            combine: Some("lhs".into()),
            samples: Some(8),
            seed: Some(3),
        };
        let rows = variants(&loc(), &spec, &vary).unwrap();
        assert_eq!(rows.len(), 8);
        for (p, lo, w) in [("a", 0.0, 1.0), ("b", 10.0, 10.0)] {
            let mut strata: Vec<usize> = rows
                .iter()
                .map(|r| ((r[p].as_float().unwrap() - lo) / w * 8.0) as usize)
                .collect();
            strata.sort();
            assert_eq!(strata, (0..8).collect::<Vec<_>>(), "{p}");
        }
        // reproducible from the seed
        assert_eq!(rows, variants(&loc(), &spec, &vary).unwrap());
    }

    #[test]
    fn grid_counts_and_orders_combinations() {
        let vary = vec![
            (
                "a".to_string(),
                Variation::List(vec![Value::Integer(1), Value::Integer(2)]),
            ),
            (
                "b".to_string(),
                Variation::Range {
                    from: 0.0,
                    to: 1.0,
                    steps: 3,
                },
            ),
        ];
        let rows = variants(&loc(), &SweepSpec::default(), &vary).unwrap();
        let got: Vec<(i64, f64)> = rows
            .iter()
            .map(|r| (r["a"].as_integer().unwrap(), r["b"].as_float().unwrap()))
            .collect();
        assert_eq!(
            got,
            [(1, 0.0), (1, 0.5), (1, 1.0), (2, 0.0), (2, 0.5), (2, 1.0)]
        );
    }
}
