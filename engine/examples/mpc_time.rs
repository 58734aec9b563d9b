//! Times MPC solves over a trot's sequence and compares ADMM with clarabel
//! (diagnosis only).
use quadsim_engine::control::mpc::{Mpc, MpcParams, MpcSolver, trot_benchmark_problem_at};
fn main() {
    let params = MpcParams::default();
    let mut admm = Mpc::new(params);
    let mut clar = Mpc::new(MpcParams {
        solver: MpcSolver::Clarabel,
        ..params
    });
    let mut times = Vec::new();
    let mut its = Vec::new();
    let mut worst: f64 = 0.0;
    for s in 0..200 {
        let pb = trot_benchmark_problem_at(&params, 0.02 * s as f64);
        let t = std::time::Instant::now();
        let f = admm.solve(&pb).unwrap();
        times.push(t.elapsed().as_secs_f64() * 1e6);
        its.push(admm.admm_iterations());
        let fc = clar.solve(&pb).unwrap();
        for k in 0..4 {
            worst = worst.max((f[k] - fc[k]).length());
        }
    }
    times.sort_by(f64::total_cmp);
    its.sort();
    println!(
        "admm median {:.1} us, p90 {:.1}, iterations median {} max {}, worst first-force difference to clarabel {worst:.3} N",
        times[100], times[180], its[100], its[199]
    );
}
