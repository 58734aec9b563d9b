//! The variation syntax shared by herds (`[herds.vary]`) and studies: a
//! scenario value named by a path takes a list of values, an evenly spaced
//! range, or random draws.
//!
//! ```toml
//! "model" = ["quad16", "quad12"]                            # a list
//! "controller.v_x_mps" = { from = 0.3, to = 0.6, steps = 4 } # 0.3, 0.4, 0.5, 0.6
//! "params.torso.mass_kg" = { uniform = [9.0, 11.0] }         # one draw per variant
//! ```
//!
//! Paths are dot-separated keys, with `[i]` for array items
//! (`robots[0].controller.kind`); after a `params` segment the rest of the
//! path is one key, since model parameter names contain dots
//! (`params.thigh.length_m`).

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use toml::{Table, Value};

/// One varied value.
#[derive(Debug, Clone, PartialEq)]
pub enum Variation {
    /// Explicit values, in order.
    List(Vec<Value>),
    /// `steps` evenly spaced numbers from `from` to `to`, both included.
    Range {
        /// First value.
        from: f64,
        /// Last value.
        to: f64,
        /// Number of values (≥ 1; 1 gives `from`).
        steps: usize,
    },
    /// Independent uniform draws in `[lo, hi)`, one per variant.
    Uniform {
        /// Lower bound.
        lo: f64,
        /// Upper bound.
        hi: f64,
    },
}

impl Variation {
    /// Parses a variation; the error says what is wrong (the caller names the path).
    pub fn parse(v: &Value) -> Result<Variation, String> {
        match v {
            Value::Array(items) if items.is_empty() => Err("an empty list varies nothing".into()),
            Value::Array(items) => Ok(Variation::List(items.clone())),
            Value::Table(t) => {
                let num = |k: &str| -> Result<f64, String> {
                    let x = t
                        .get(k)
                        .and_then(crate::scenario::validate::as_f64)
                        .ok_or_else(|| format!("`{k}` must be a number"))?;
                    if x.is_finite() {
                        Ok(x)
                    } else {
                        Err(format!("`{k}` must be finite"))
                    }
                };
                let keys: Vec<&str> = t.keys().map(String::as_str).collect();
                if let Some(u) = t.get("uniform") {
                    if keys.len() != 1 {
                        return Err("a `uniform` draw takes no other keys".into());
                    }
                    let b = match u.as_array().map(|a| a.as_slice()) {
                        Some([lo, hi]) => (
                            crate::scenario::validate::as_f64(lo),
                            crate::scenario::validate::as_f64(hi),
                        ),
                        _ => (None, None),
                    };
                    return match b {
                        (Some(lo), Some(hi)) if lo.is_finite() && hi.is_finite() && lo < hi => {
                            Ok(Variation::Uniform { lo, hi })
                        }
                        (Some(lo), Some(hi)) if lo.is_finite() && hi.is_finite() => Err(format!(
                            "`uniform = [{lo}, {hi}]` is an empty range: the lower bound must be below the upper"
                        )),
                        _ => Err("`uniform` must be [lower, upper], two finite numbers".into()),
                    };
                }
                if t.contains_key("from") || t.contains_key("to") || t.contains_key("steps") {
                    if let Some(k) = keys.iter().find(|k| !["from", "to", "steps"].contains(k)) {
                        return Err(format!("unknown key `{k}` in a range (from, to, steps)"));
                    }
                    let (from, to) = (num("from")?, num("to")?);
                    let steps = t
                        .get("steps")
                        .and_then(Value::as_integer)
                        .ok_or("`steps` must be a positive integer")?;
                    if steps < 1 {
                        return Err(format!(
                            "`steps = {steps}` is an empty range: it must be ≥ 1"
                        ));
                    }
                    return Ok(Variation::Range {
                        from,
                        to,
                        steps: steps as usize,
                    });
                }
                Err("expected a list, { from, to, steps } or { uniform = [lo, hi] }".into())
            }
            other => Err(format!(
                "expected a list, {{ from, to, steps }} or {{ uniform = [lo, hi] }}, not the single value {other}: \
                 a value that does not vary belongs in the template"
            )),
        }
    }

    /// Number of distinct values (`None` for random draws).
    pub fn count(&self) -> Option<usize> {
        match self {
            Variation::List(v) => Some(v.len()),
            Variation::Range { steps, .. } => Some(*steps),
            Variation::Uniform { .. } => None,
        }
    }

    /// Value number `k` (modulo the count); random draws come from `rng`.
    pub fn value(&self, k: usize, rng: &mut ChaCha8Rng) -> Value {
        match self {
            Variation::List(v) => v[k % v.len()].clone(),
            Variation::Range { from, to, steps } => {
                let k = k % steps;
                let x = if *steps == 1 {
                    *from
                } else {
                    from + (to - from) * k as f64 / (*steps - 1) as f64
                };
                Value::Float(x)
            }
            Variation::Uniform { lo, hi } => Value::Float(rng.random_range(*lo..*hi)),
        }
    }
}

/// A random stream for draw `path` of variant `variant` (independent of the
/// order of variants and paths).
pub fn draw_rng(seed: u64, variant: &str, path: &str) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(crate::seed::stream_seed(seed, &format!("{variant}/{path}")))
}

/// One segment of a path: a key, optionally indexed (`robots[2]`).
fn segments(path: &str) -> Result<Vec<(String, Option<usize>)>, String> {
    let mut out = Vec::new();
    let mut rest = path;
    while !rest.is_empty() {
        let (seg, tail) = match rest.find('.') {
            Some(i) => (&rest[..i], &rest[i + 1..]),
            None => (rest, ""),
        };
        let (key, index) = match seg.find('[') {
            Some(b) if seg.ends_with(']') => {
                let i = seg[b + 1..seg.len() - 1]
                    .parse::<usize>()
                    .map_err(|_| format!("bad index in `{seg}`"))?;
                (&seg[..b], Some(i))
            }
            _ => (seg, None),
        };
        if key.is_empty() {
            return Err(format!("empty key in path `{path}`"));
        }
        out.push((key.to_string(), index));
        if key == "params" && index.is_none() && !tail.is_empty() {
            out.push((tail.to_string(), None));
            break;
        }
        rest = tail;
    }
    if out.is_empty() {
        return Err("empty path".into());
    }
    Ok(out)
}

/// The value at `path` in `table`, if there is one.
pub fn get_path<'a>(table: &'a Table, path: &str) -> Option<&'a Value> {
    let segs = segments(path).ok()?;
    let mut cur: Option<&Value> = None;
    for (key, index) in &segs {
        let t = match cur {
            None => table,
            Some(v) => v.as_table()?,
        };
        let mut v = t.get(key)?;
        if let Some(i) = index {
            v = v.as_array()?.get(*i)?;
        }
        cur = Some(v);
    }
    cur
}

/// Sets the value at `path` in `table`, creating missing tables on the way
/// (the result is type-checked when it is read as a scenario). Array items
/// must exist.
pub fn set_path(table: &mut Table, path: &str, value: Value) -> Result<(), String> {
    let segs = segments(path)?;
    let mut cur = table;
    for (n, (key, index)) in segs.iter().enumerate() {
        let last = n + 1 == segs.len();
        match index {
            None if last => {
                cur.insert(key.clone(), value);
                return Ok(());
            }
            None => {
                let entry = cur
                    .entry(key.clone())
                    .or_insert_with(|| Value::Table(Table::new()));
                cur = entry
                    .as_table_mut()
                    .ok_or_else(|| format!("`{key}` in `{path}` is not a table"))?;
            }
            Some(i) => {
                let arr = cur
                    .get_mut(key)
                    .and_then(Value::as_array_mut)
                    .ok_or_else(|| format!("`{key}` in `{path}` is not an array"))?;
                let len = arr.len();
                let item = arr
                    .get_mut(*i)
                    .ok_or_else(|| format!("`{key}[{i}]` in `{path}`: there are only {len}"))?;
                if last {
                    *item = value;
                    return Ok(());
                }
                cur = item
                    .as_table_mut()
                    .ok_or_else(|| format!("`{key}[{i}]` in `{path}` is not a table"))?;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(s: &str) -> Value {
        toml::from_str::<Table>(&format!("x = {s}")).unwrap()["x"].clone()
    }

    #[test]
    fn ranges_include_both_ends_and_cycle() {
        let r = Variation::parse(&v("{ from = 0.3, to = 0.6, steps = 4 }")).unwrap();
        let mut rng = draw_rng(1, "a", "b");
        let xs: Vec<f64> = (0..5)
            .map(|k| r.value(k, &mut rng).as_float().unwrap())
            .collect();
        let want = [0.3, 0.4, 0.5, 0.6, 0.3];
        for (x, w) in xs.iter().zip(want) {
            assert!((x - w).abs() < 1e-15, "{xs:?}");
        }
        assert_eq!(r.count(), Some(4));
    }

    #[test]
    fn uniform_draws_stay_in_range_and_depend_on_the_variant_only() {
        let u = Variation::parse(&v("{ uniform = [2.0, 3.0] }")).unwrap();
        let a = u.value(0, &mut draw_rng(7, "h-001", "p"));
        let b = u.value(5, &mut draw_rng(7, "h-001", "p"));
        let c = u.value(0, &mut draw_rng(7, "h-002", "p"));
        assert_eq!(a, b);
        assert_ne!(a, c);
        let x = a.as_float().unwrap();
        assert!((2.0..3.0).contains(&x));
    }

    #[test]
    fn bad_variations_say_why() {
        for (src, msg) in [
            ("[]", "empty list"),
            ("{ from = 1.0, to = 2.0, steps = 0 }", "empty range"),
            ("{ uniform = [3.0, 1.0] }", "empty range"),
            ("{ uniform = [1.0] }", "two finite numbers"),
            (
                "{ from = 1.0, to = 2.0, steps = 2, by = 1 }",
                "unknown key `by`",
            ),
            ("0.5", "single value"),
        ] {
            let e = Variation::parse(&v(src)).unwrap_err();
            assert!(e.contains(msg), "{src}: {e}");
        }
    }

    #[test]
    fn paths_set_nested_keys_params_and_array_items() {
        let mut t: Table = toml::from_str(
            "model = \"quad16\"\n[[robots]]\nname = \"a\"\n[robots.controller]\nkind = \"vmc\"\n",
        )
        .unwrap();
        set_path(&mut t, "robots[0].controller.v_x_mps", Value::Float(0.7)).unwrap();
        set_path(
            &mut t,
            "robots[0].params.thigh.length_m",
            Value::Float(0.31),
        )
        .unwrap();
        set_path(&mut t, "model", Value::String("quad12".into())).unwrap();
        let r = &t["robots"][0];
        assert_eq!(r["controller"]["v_x_mps"].as_float(), Some(0.7));
        assert_eq!(
            get_path(&t, "robots[0].params.thigh.length_m").and_then(Value::as_float),
            Some(0.31)
        );
        assert_eq!(get_path(&t, "robots[1].name"), None);
        assert_eq!(r["params"]["thigh.length_m"].as_float(), Some(0.31));
        assert_eq!(t["model"].as_str(), Some("quad12"));
        let e = set_path(&mut t, "robots[3].name", Value::Float(1.0)).unwrap_err();
        assert!(e.contains("only 1"), "{e}");
        let e = set_path(&mut t, "model.x", Value::Float(1.0)).unwrap_err();
        assert!(e.contains("not a table"), "{e}");
    }
}
