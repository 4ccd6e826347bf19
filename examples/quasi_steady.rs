//! How far the quasi-steady approximation of the ramps is from the full model, per
//! channel in units of that channel's noise σ:
//! `cargo run --release --example quasi_steady [DATASET_DIR]` (the shipped dataset without
//! one; `MOTOR=leaky` for 3× the cross leak and 2× the friction).
//!
//! For the dataset's nominal motor it prints, for each channel, the largest deviation of
//! the default Rodas4, of the quasi-steady states with their first-order lag and of the
//! bare steady states from an rtol-1e-12 Rodas4 reference, and the cost of each; then
//! the motor's time constants (−1/Re λ of ∂f/∂x at the free steady state) at a few supply
//! pressures under the ramps' brake, which say why the approximation fails near breakaway.
use std::path::PathBuf;
use vanefit::data::Dataset;
use vanefit::model::{Boundary, EffectSet, Load, Motor};
use vanefit::numerics::{QuasiSteady, Rodas4, StiffSolver, Tolerances};
use vanefit::objective::{ChannelResiduals, CostModel, CostOptions};
use vanefit::sim::steady;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = std::env::args().nth(1).map_or_else(
        || PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("measurements/ar034-synthetic"),
        PathBuf::from,
    );
    let ds = Dataset::load(&dir)?;
    let cost = CostModel::new(&ds, CostOptions::default())?;
    let nominal = ds.nominal_params()?;
    let params = if std::env::var("MOTOR").as_deref() == Ok("leaky") {
        nominal
            .with("c_12", 3.0 * nominal.c_12())?
            .with("t_coulomb", 2.0 * nominal.t_coulomb())?
    } else {
        nominal
    };
    let motor = Motor::new(params, EffectSet::empty());
    let tight = Rodas4 {
        tol: Tolerances::with_rtol(1e-12),
    };
    let reference = cost.residuals(&motor, &tight)?;
    let cases: [(&str, Box<dyn StiffSolver>); 3] = [
        ("rodas4", Box::new(Rodas4::default())),
        ("quasi-steady", Box::new(QuasiSteady::default())),
        (
            "steady only",
            Box::new(QuasiSteady {
                lag: false,
                ..QuasiSteady::default()
            }),
        ),
    ];
    println!("dataset {}", dir.display());
    for (name, solver) in &cases {
        let res = cost.residuals(&motor, solver.as_ref())?;
        let total = cost.evaluate(&motor, solver.as_ref()).total;
        println!("{name}: cost {total:.10}");
        for (a, b) in reference.iter().zip(&res) {
            let (dev, row) = worst(a, b);
            println!(
                "  {:<28} {:<10} max dev {dev:.2e} σ (row {row})",
                a.file, a.column
            );
        }
    }
    time_constants(&motor)?;
    Ok(())
}

/// The time constants at the free steady state for supply pressures from 0.12 to 0.73 MPa,
/// with the ramps' brake (1e-4 N·m·s/rad).
fn time_constants(motor: &Motor) -> Result<(), Box<dyn std::error::Error>> {
    println!("p_supply (MPa)  speed (rad/s)  time constants (ms), largest first");
    for p_mpa in [0.12, 0.13, 0.14, 0.15, 0.2, 0.3, 0.5, 0.73] {
        let load = Load::ViscousBrake { c_nm_s_rad: 1e-4 };
        let bc = Boundary::supplied(p_mpa * 1e6, 101_325.0, load);
        let x = steady::free(motor, &bc, &steady::initial_guess(&bc))?;
        let jac = motor.jacobian(&x, &bc).ok_or("no analytic Jacobian")?;
        let m = nalgebra::Matrix4::from_fn(|i, k| jac[i][k]);
        let mut tau: Vec<f64> = m
            .complex_eigenvalues()
            .iter()
            .map(|l| -1e3 / l.re)
            .collect();
        tau.sort_by(|a, b| b.total_cmp(a));
        println!("{p_mpa:14.2}  {:13.2}  {tau:.3?}", x[3]);
    }
    Ok(())
}

/// The largest |a − b|/σ of one channel and its row.
fn worst(a: &ChannelResiduals, b: &ChannelResiduals) -> (f64, usize) {
    a.simulated
        .iter()
        .zip(&b.simulated)
        .enumerate()
        .map(|(i, (u, v))| ((u - v).abs() / a.sigma, a.rows[i]))
        .fold((0.0, 0), |w, d| if d.0 > w.0 { d } else { w })
}
