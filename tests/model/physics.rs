//! Physics the simulation core must reproduce: limits, conservation, symmetry, closed forms,
//! and the default motor's published figures (docs/model.md).

use proptest::prelude::*;
use std::f64::consts::PI;
use vanefit::data::{free_speed, plan_experiments, SynthPlan};
use vanefit::model::MotorParams;
use vanefit::model::{idx, Boundary, Load, Motor, State};
use vanefit::model::{psi, Nozzle, R_LAMINAR};
use vanefit::model::{Effect, EffectSet};
use vanefit::numerics::DefaultSolver;
use vanefit::numerics::{DiffsolBdf, StiffSolver, Tolerances};
use vanefit::sim::steady;
use vanefit::sim::Experiment;
use vanefit::units::Quantity;

const P_ATM: f64 = 101_325.0;
const P_SUPPLY: f64 = 0.73e6;

fn default_bc() -> Boundary {
    Boundary::supplied(P_SUPPLY, P_ATM, Load::None)
}

/// Shaft torque and port-1 flow of the default motor at imposed speeds.
fn characteristic(motor: &Motor, speeds: &[f64]) -> Vec<(f64, f64)> {
    let bc = default_bc();
    let mut guess = steady::initial_guess(&bc);
    speeds
        .iter()
        .map(|w| {
            let x = steady::at_speed(motor, &bc, *w, &guess).unwrap();
            guess = x;
            let b = motor.balance(&x, &bc);
            // At standstill the full dry friction holds against the motor (stall torque).
            let torque = if *w == 0.0 {
                b.torque_ideal_nm - motor.friction_at_rest(x[idx::P1], x[idx::PE])
            } else {
                b.torque_shaft_nm()
            };
            (torque, b.flow_port1_kg_s)
        })
        .collect()
}

#[test]
fn default_motor_reproduces_spec_figures() {
    let m = Motor::default_motor();
    let w_free = free_speed(&m, P_SUPPLY, P_ATM).unwrap();
    let rpm_free = w_free * 30.0 / PI;
    assert!(
        (rpm_free / 12_000.0 - 1.0).abs() < 0.10,
        "free speed {rpm_free} rpm"
    );
    let speeds: Vec<f64> = (0..=200).map(|k| w_free * f64::from(k) / 200.0).collect();
    let curve = characteristic(&m, &speeds);
    let (stall_torque, standstill_flow) = curve[0];
    assert!(
        (stall_torque / 0.31 - 1.0).abs() < 0.10,
        "stall torque {stall_torque}"
    );
    assert!(
        (standstill_flow / 2.3e-3 - 1.0).abs() < 0.10,
        "standstill flow {standstill_flow}"
    );
    let (k_peak, p_peak) = curve
        .iter()
        .zip(&speeds)
        .map(|((t, _), w)| t * w)
        .enumerate()
        .fold(
            (0, 0.0),
            |best, (k, p)| if p > best.1 { (k, p) } else { best },
        );
    assert!((p_peak / 100.0 - 1.0).abs() < 0.10, "peak power {p_peak} W");
    let at = speeds[k_peak] / w_free;
    eprintln!(
        "default motor: stall torque {stall_torque:.4} N*m, standstill flow {:.3} g/s, free speed {rpm_free:.0} rpm, peak power {p_peak:.1} W at {at:.2} of free speed",
        standstill_flow * 1e3
    );
    assert!((at - 0.5).abs() < 0.1, "peak power at {at} of free speed");
    // Shaft torque at free speed is zero (the free-running steady state has no load).
    assert!(curve[200].0.abs() < 1e-6);
}

#[test]
fn torque_falls_almost_linearly_over_upper_speed_range() {
    let m = Motor::default_motor();
    let w_free = free_speed(&m, P_SUPPLY, P_ATM).unwrap();
    let speeds: Vec<f64> = (0..=40)
        .map(|k| w_free * (0.25 + 0.75 * f64::from(k) / 40.0))
        .collect();
    let torque: Vec<f64> = characteristic(&m, &speeds).iter().map(|c| c.0).collect();
    let n = speeds.len() as f64;
    let (mx, my) = (
        speeds.iter().sum::<f64>() / n,
        torque.iter().sum::<f64>() / n,
    );
    let sxy: f64 = speeds
        .iter()
        .zip(&torque)
        .map(|(x, y)| (x - mx) * (y - my))
        .sum();
    let sxx: f64 = speeds.iter().map(|x| (x - mx).powi(2)).sum();
    let syy: f64 = torque.iter().map(|y| (y - my).powi(2)).sum();
    let r2 = sxy * sxy / (sxx * syy);
    assert!(sxy < 0.0, "torque must fall with speed");
    assert!(r2 > 0.99, "R² of a straight line {r2}");
}

#[test]
fn reversible_motor_supplied_at_port_2_runs_backwards_at_same_speed() {
    let m = Motor::default_motor();
    let load = Load::ViscousBrake { c_nm_s_rad: 1e-4 };
    let fwd_bc = Boundary::supplied(P_SUPPLY, P_ATM, load);
    let rev_bc = Boundary {
        p_port1_pa: P_ATM,
        p_port2_pa: P_SUPPLY,
        ..fwd_bc
    };
    let fwd = steady::free(&m, &fwd_bc, &steady::initial_guess(&fwd_bc)).unwrap();
    let rev = steady::free(&m, &rev_bc, &[P_ATM, P_SUPPLY, P_ATM, 0.0]).unwrap();
    assert!(fwd[idx::OMEGA] > 100.0);
    assert!(
        (rev[idx::OMEGA] + fwd[idx::OMEGA]).abs() < 1e-6 * fwd[idx::OMEGA],
        "{rev:?} vs {fwd:?}"
    );
    assert!((rev[idx::P2] - fwd[idx::P1]).abs() < 1e-3);
    assert!((rev[idx::P1] - fwd[idx::P2]).abs() < 1e-3);
}

#[test]
fn transient_held_at_constant_speed_settles_on_newton_steady_state() {
    let m = Motor::default_motor();
    let bc = default_bc();
    let omega = 600.0;
    let newton = steady::at_speed(&m, &bc, omega, &steady::initial_guess(&bc)).unwrap();
    let rhs = |_t: f64, x: &State| {
        let mut d = m.derivatives(x, &bc);
        d[idx::OMEGA] = 0.0; // speed imposed, as on a datasheet test bench
        d
    };
    let x0 = [P_ATM, P_ATM, P_ATM, omega];
    let solver = DiffsolBdf {
        tol: Tolerances {
            rtol: 1e-9,
            atol: [1e-3, 1e-3, 1e-3, 1e-6],
        },
    };
    let xs = solver.solve(&rhs, 0.0, x0, &[0.5]).unwrap();
    for i in 0..3 {
        assert!(
            (xs[0][i] - newton[i]).abs() < 1e-3 * newton[i] * 1e-3,
            "state {i}: {} vs {}",
            xs[0][i],
            newton[i]
        );
    }
}

#[test]
fn gear_motor_limit_in_full_model() {
    // With ε = 1 the ideal torque at any state is z(p1 − p2)(V_fill − V_d)/(2π) forward.
    let p = MotorParams::default().with("eps", 1.0).unwrap();
    let m = Motor::new(p.clone(), EffectSet::empty());
    let bc = default_bc();
    let x = [6.0e5, 1.6e5, 1.4e5, 500.0];
    let b = m.balance(&x, &bc);
    let gear = p.z() * (x[0] - x[1]) * (p.v_disp() / p.z() - p.v_dead()) / (2.0 * PI);
    let w = 0.5 * (1.0 + 500f64.tanh());
    let rev = -p.z() * (x[1] - x[0]) * (p.v_disp() / p.z() - p.v_dead()) / (2.0 * PI);
    assert!((b.torque_ideal_nm - (w * gear + (1.0 - w) * rev)).abs() < 1e-12);
}

#[test]
fn default_solver_agrees_with_an_independent_tight_integration() {
    // Both transient experiments with the default solver (Rodas4 with the analytic Jacobian)
    // against diffsol's BDF at rtol 1e-10 (a different method, finite-difference Jacobian):
    // the outputs agree to a hundredth of typical sensor noise (0.03 g/s on flows, 15 rpm on
    // speed, 4 mN·m on torque).
    let m = Motor::default_motor();
    let w_free = free_speed(&m, P_SUPPLY, P_ATM).unwrap();
    let plan = SynthPlan::default();
    let tight = DiffsolBdf {
        tol: Tolerances {
            rtol: 1e-10,
            atol: [1e-4, 1e-4, 1e-4, 1e-7],
        },
    };
    for data in &plan_experiments(&plan, w_free)[1..] {
        let ex = Experiment::new(data, P_ATM).unwrap();
        let ours = ex.simulate(&m, &DefaultSolver::default()).unwrap();
        let reference = ex.simulate(&m, &tight).unwrap();
        for ((q, a), (_, b)) in ours.outputs.iter().zip(&reference.outputs) {
            let sigma = match q {
                Quantity::Flow1 | Quantity::Flow2 => 3e-5,
                Quantity::Speed => 15.0 * 2.0 * PI / 60.0,
                _ => 4e-3,
            };
            let worst = a
                .iter()
                .zip(b)
                .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()));
            assert!(worst < 0.01 * sigma, "{:?} {q:?}: {worst:e}", ex.kind);
        }
    }
}

fn arb_state() -> impl Strategy<Value = State> {
    (
        2e4..1.2e6f64,
        2e4..1.2e6f64,
        2e4..1.2e6f64,
        -2500.0..2500.0f64,
    )
        .prop_map(|(a, b, c, w)| [a, b, c, w])
}

fn arb_effects() -> impl Strategy<Value = EffectSet> {
    proptest::collection::vec(0..Effect::ALL.len(), 0..4)
        .prop_map(|ix| ix.into_iter().map(|i| Effect::ALL[i]).collect())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(400))]

    /// Mass is conserved at every right-hand-side evaluation: what the three volumes store is
    /// exactly what the ports exchange with the surroundings, with any effect switched on.
    #[test]
    fn mass_is_conserved(x in arb_state(), p_sup in 1.1e5..1e6f64, c2 in proptest::option::of(1e-10..1e-7f64), fx in arb_effects()) {
        let m = Motor::new(MotorParams::default(), fx);
        let mut bc = Boundary::supplied(p_sup, P_ATM, Load::ViscousBrake { c_nm_s_rad: 1e-4 });
        bc.c_port2_m3_s_pa = c2;
        let b = m.balance(&x, &bc);
        let stored = b.dm1_kg_s + b.dm2_kg_s + b.dme_kg_s;
        let exchanged = b.flow_port1_kg_s - b.flow_port2_kg_s - b.flow_exhaust_kg_s;
        prop_assert!((stored - exchanged).abs() <= 1e-12 * (b.flow_port1_kg_s.abs() + b.flow_port2_kg_s.abs() + b.flow_exhaust_kg_s.abs() + 1e-9));
        let d = m.derivatives(&x, &bc);
        prop_assert!(d.iter().all(|v| v.is_finite()));
    }

    /// Nozzle flow is continuous and monotone in both pressures and antisymmetric.
    #[test]
    fn nozzle_is_monotone_and_antisymmetric(p_u in 1e4..2e6f64, r in 0.0..1.0f64, b in 0.1..0.9f64, c in 1e-10..1e-7f64) {
        let n = Nozzle::new(c, b);
        let p_d = p_u * r;
        prop_assert_eq!(n.flow(p_u, p_d), -n.flow(p_d, p_u));
        let dp = 1e-6 * p_u;
        prop_assert!(n.flow(p_u + dp, p_d) >= n.flow(p_u, p_d));
        prop_assert!(n.flow(p_u, p_d + dp) <= n.flow(p_u, p_d));
        prop_assert!(n.flow(p_u, p_d) >= 0.0);
    }

    /// Cycle work is positive at every steady operating point of a driven motor.
    #[test]
    fn driven_motor_does_positive_work(p_sup in 2.0e5..1.0e6f64, frac in 0.0..0.98f64) {
        let m = Motor::default_motor();
        let w_free = free_speed(&m, p_sup, P_ATM).unwrap();
        let bc = Boundary::supplied(p_sup, P_ATM, Load::None);
        let x = steady::at_speed(&m, &bc, frac * w_free, &steady::initial_guess(&bc)).unwrap();
        prop_assert!(x[idx::P1] > x[idx::P2]);
        prop_assert!(m.cycle().work(x[idx::P1], x[idx::P2], x[idx::PE]) > 0.0);
    }
}

#[test]
fn psi_is_continuous_across_b_and_laminar_threshold_on_a_fine_grid() {
    for b in [0.3, 0.5, 0.528] {
        let mut last = psi(0.0, b);
        let n = 200_000;
        for k in 1..=n {
            let r = f64::from(k) / f64::from(n);
            let v = psi(r, b);
            assert!(v <= last + 1e-15, "not monotone at r = {r}");
            // Largest jump between neighbours: bounded by the steepest slope (≈ 63 near r_lam).
            assert!(
                last - v < 100.0 / f64::from(n),
                "jump at r = {r}: {last} -> {v}"
            );
            last = v;
        }
        assert!(psi(R_LAMINAR, b) > 0.0);
    }
}
