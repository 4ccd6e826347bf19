//! Accuracy, smoothness and speed of the stiff solvers on the shipped dataset (how the
//! default solver and its tolerance were chosen):
//! `cargo run --release --example solver_accuracy [n_timing]`.
//!
//! For each solver and tolerance it prints the time of one full cost evaluation, the
//! right-hand-side evaluations behind it, the largest deviation of any simulated output from
//! a tight-tolerance reference run in units of that channel's noise σ, and the cost jitter:
//! the largest residual of a quadratic fitted to the cost at 21 values of c_12, t_coulomb
//! and c_in1 each spread over ±1e-5 relative (a smooth cost leaves only rounding there), and
//! the cost's difference from the reference run's cost (its bias, which moves the fits).
//! `GRID="rtol,atol_p,atol_w;…"` sets the Rodas4 tolerances to try (or
//! `rtol,atol_p1,atol_p2,atol_pe,atol_w` with one absolute tolerance per state), `MOTOR=leaky` a motor
//! far from the data.
#[path = "common/support.rs"]
mod support;

use vanefit::model::EffectSet;
use vanefit::model::Motor;
use vanefit::model::MotorParams;
use vanefit::numerics::Rodas4;
use vanefit::numerics::{DiffsolBdf, StiffSolver, Tolerances};
use vanefit::objective::CostModel;

fn outputs(cost: &CostModel, motor: &Motor, solver: &dyn StiffSolver) -> Vec<(f64, Vec<f64>)> {
    let res = cost.residuals(motor, solver).expect("simulation");
    res.into_iter().map(|c| (c.sigma, c.simulated)).collect()
}

fn max_dev_sigma(a: &[(f64, Vec<f64>)], b: &[(f64, Vec<f64>)]) -> f64 {
    let mut worst = (0.0, 0, 0);
    for (c, ((s, x), (_, y))) in a.iter().zip(b).enumerate() {
        for (i, (u, v)) in x.iter().zip(y).enumerate() {
            let d = (u - v).abs() / s;
            if d > worst.0 {
                worst = (d, c, i);
            }
        }
    }
    if std::env::var("WHERE").is_ok() {
        eprintln!("worst: channel {} row {}", worst.1, worst.2);
    }
    worst.0
}

/// Largest residual of a least-squares quadratic through the cost at 21 values of each of
/// c_12, t_coulomb and c_in1 spread over ±1e-5 relative (the largest over the three).
fn jitter(cost: &CostModel, params: &MotorParams, solver: &dyn StiffSolver) -> f64 {
    let us: Vec<f64> = (-10..=10).map(|k| f64::from(k) * 1e-6).collect();
    let a = nalgebra::DMatrix::from_fn(us.len(), 3, |i, j| (us[i] * 1e5).powi(j as i32));
    let mut worst: f64 = 0.0;
    for name in ["c_12", "t_coulomb", "c_in1"] {
        let v = params.get(name).unwrap();
        let js: Vec<f64> = us
            .iter()
            .map(|u| {
                let p = params.with(name, v * (1.0 + u)).unwrap();
                cost.evaluate(&Motor::new(p, EffectSet::empty()), solver)
                    .total
            })
            .collect();
        let b = nalgebra::DVector::from_vec(js);
        let coef = a.clone().svd(true, true).solve(&b, 1e-14).unwrap();
        worst = worst.max((&a * coef - b).amax());
    }
    worst
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let (n, ds, cost) = support::shipped(100)?;
    let nominal = ds.nominal_params()?;
    let which = std::env::var("MOTOR").unwrap_or_default();
    let params = match which.as_str() {
        "default" => MotorParams::default(),
        "leaky" => nominal
            .with("c_12", 3.0 * nominal.c_12())?
            .with("t_coulomb", 2.0 * nominal.t_coulomb())?,
        _ => nominal,
    };
    println!(
        "motor: {}",
        if which.is_empty() { "nominal" } else { &which }
    );
    let motor = Motor::new(params.clone(), EffectSet::empty());
    let tight = Rodas4 {
        tol: Tolerances::with_rtol(1e-12),
    };
    let reference = outputs(&cost, &motor, &tight);
    // The cost's bias: every row's error summed, which the largest deviation does not show
    // (a change of the step sequence moves it by 1e-5 either way, and the fits with it).
    let reference_cost = cost.evaluate(&motor, &tight).total;
    let check = outputs(
        &cost,
        &motor,
        &DiffsolBdf {
            tol: Tolerances::with_rtol(1e-12),
        },
    );
    println!(
        "reference: Rodas4 rtol 1e-12; BDF rtol 1e-12 differs from it by {:.2e} σ",
        max_dev_sigma(&reference, &check)
    );
    println!("reference cost {reference_cost:.10}");
    println!(
        "solver  rtol,atol_p,atol_w  µs/eval  rhs/eval  max dev (σ)  jitter (cost)  cost  cost − reference"
    );
    let mut cases: Vec<(&str, String, Box<dyn StiffSolver>)> = Vec::new();
    cases.push(("bdf", "3e-8".into(), Box::new(DiffsolBdf::default())));
    if std::env::var("GRID").is_err() {
        let tol = Rodas4::default().tol;
        let name = format!("{:.0e},{},{}", tol.rtol, tol.atol[0], tol.atol[3]);
        cases.push(("rodas4", name, Box::new(Rodas4::default())));
    }
    let grid = std::env::var("GRID").unwrap_or_default();
    for item in grid.split(';').filter(|i| !i.is_empty()) {
        let v: Vec<f64> = item.split(',').map(|x| x.parse().unwrap()).collect();
        // Three numbers: rtol, atol on every pressure, atol on speed; five: rtol, then
        // atol on p_1, p_2, p_e and ω each.
        let atol = if v.len() == 5 {
            [v[1], v[2], v[3], v[4]]
        } else {
            [v[1], v[1], v[1], v[2]]
        };
        let tol = Tolerances { rtol: v[0], atol };
        cases.push(("rodas4", item.to_string(), Box::new(Rodas4 { tol })));
    }
    for (name, rtol, solver) in &cases {
        let (c, calls, us) = support::count_and_time(&cost, &motor, solver.as_ref(), n);
        let dev = max_dev_sigma(&reference, &outputs(&cost, &motor, solver.as_ref()));
        let jit = jitter(&cost, &params, solver.as_ref());
        println!(
            "{name:7} {rtol:18}  {us:7.1}  {calls:8}  {dev:11.2e}  {jit:13.2e}  {:.8}  {:+.2e}",
            c.total,
            c.total - reference_cost
        );
    }
    Ok(())
}
