//! quad16 trots over sinusoidal terrain through the whole pipeline:
//! `scenarios/trot_sine.toml` (amplitude 5 cm, wavelength 2 m, from x = 1 m;
//! 0.5 m/s) does not fall in 10 s, and its speed on the waves is at least
//! 80 % of the flat trot's (`scenarios/trot.toml`, the same command): the
//! mean speed along the start heading over t ∈ [4, 10] s, when the robot is
//! on the waves (it reaches them at about 2.5 s).

use std::path::Path;

use quadsim::analysis::{Trace, run_trace};
use quadsim::scenario::load_scenario;

fn speed_4_to_10(tr: &Trace) -> f64 {
    let i4 = tr.t_s.iter().position(|t| *t >= 4.0).unwrap();
    let i10 = tr.t_s.len() - 1;
    (tr.forward_m[i10] - tr.forward_m[i4]) / (tr.t_s[i10] - tr.t_s[i4])
}

#[test]
fn quad16_trots_over_sinusoidal_terrain() {
    let sine = load_scenario(Path::new("scenarios/trot_sine.toml")).unwrap();
    let flat = load_scenario(Path::new("scenarios/trot.toml")).unwrap();
    let ts = run_trace(&sine, "rex", None, None, 0.0).unwrap();
    let tf = run_trace(&flat, "rex", None, None, 0.0).unwrap();
    assert!(ts.fell_at_s.is_none(), "fell at {:?}", ts.fell_at_s);
    assert!(
        tf.fell_at_s.is_none(),
        "the flat trot fell at {:?}",
        tf.fell_at_s
    );
    // on the waves from t = 4 s: past x = 1 m
    let i4 = ts.t_s.iter().position(|t| *t >= 4.0).unwrap();
    assert!(
        ts.forward_m[i4] > 1.2,
        "at x = {} m at 4 s",
        ts.forward_m[i4]
    );
    let (vs, vf) = (speed_4_to_10(&ts), speed_4_to_10(&tf));
    eprintln!(
        "speed over [4, 10] s: sine {vs:.4} m/s, flat {vf:.4} m/s, ratio {:.4}",
        vs / vf
    );
    assert!(vs >= 0.8 * vf, "sine {vs} m/s vs flat {vf} m/s");
}
