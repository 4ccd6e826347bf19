//! The candidate measurements: for each kind, what a rig (or a page) would record, the
//! noise of each recorded value, and the settings a technician runs. Each candidate is a
//! vector of observables z(motor), simulated with the steady solver at settings fixed at
//! the fitted motor (so that a perturbed motor is observed at the same settings), and the
//! noise σ of each: a page's reading tolerance (`data::dataset::catalogue`, 2 % of each
//! channel's full scale, as a page's fit weighs its key figures) for key figures, the rig's sensor noise for its size otherwise
//! (`SensorNoise::typical_for`, divided by √readings where a value is averaged).
//!
//! Every observation is a steady state: a ramp slow enough to be quasi-steady, and a load
//! step's two settled levels. The transient of a step (which carries the inertia) is not
//! counted, so the information of a load step is a lower bound.

use super::options::{CandidateKind, PlanOptions};
use crate::data::dataset::catalogue::DEFAULT_TOLERANCE;
use crate::data::synth::SensorNoise;
use crate::model::motor::{Boundary, Load, Motor, State};
use crate::sim::operating_point::{at_speeds, catalogue_row, CatalogueRow, Conditions};
use crate::sim::steady;
use std::f64::consts::PI;

/// The speed grid of the catalogue rows the candidates read (1 rpm); their figures are
/// taken at the continuous optimum, which is smooth in the parameters.
pub(super) const GRID_RAD_S: f64 = PI / 30.0;
/// Speeds of a datasheet sweep, and their span as fractions of the free speed.
const SWEEP_POINTS: usize = 12;
const SWEEP_SPAN: [f64; 2] = [0.05, 0.95];
/// Points of a pressure ramp; it starts at half the lowest asked gauge pressure.
const RAMP_POINTS: usize = 16;
/// Points of an outlet-throttle ramp and its span as multiples of the fitted `c_out2`.
const THROTTLE_POINTS: usize = 10;
const THROTTLE_SPAN: [f64; 2] = [0.1, 3.0];
/// The brake's torque of a load step, as a fraction of the stall torque.
const LOAD_STEP_FRACTION: f64 = 0.5;
/// Readings averaged per value where a figure is read repeatedly (stall torque, air flow,
/// the load step's levels).
const REPEATS: usize = 5;
/// Rig time per steady point, s: settling and averaging (sets the durations printed).
const SECONDS_PER_POINT: f64 = 30.0;

/// What a technician runs: the settings of one candidate, SI.
#[derive(Debug, Clone, PartialEq)]
pub struct RigSettings {
    /// Supply pressure from and to, Pa absolute (equal for a fixed pressure).
    pub p_supply_pa: [f64; 2],
    /// Imposed shaft speeds from and to, rad/s (a datasheet sweep; motor shaft).
    pub speeds_rad_s: Option<[f64; 2]>,
    /// Outlet throttle's sonic conductance from and to, m³/(s·Pa).
    pub throttle_m3_s_pa: Option<[f64; 2]>,
    /// Brake torque from and to, N·m (motor shaft).
    pub load_nm: Option<[f64; 2]>,
    /// Steady points (settings) recorded.
    pub points: usize,
    /// Readings averaged per point.
    pub readings: usize,
    /// Rig time of the recording itself, s (setting up is in the cost).
    pub duration_s: f64,
    /// What is recorded, in words.
    pub records: &'static str,
}

/// One steady state with the shaft free (a ramp's point or a load step's level).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct FreePoint {
    p_supply_pa: f64,
    c_outlet_m3_s_pa: Option<f64>,
    load_nm: f64,
    /// The fitted motor's speed there: the Newton start of every perturbed motor.
    omega_guess: f64,
}

/// What a candidate simulates.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Design {
    /// A page's key figures as the fit reads them: points of its curves at the fitted
    /// motor's speeds 0, of maximum power and free: the stall torque, the power and air at
    /// maximum power, the torque (0) and air at free speed.
    KeyFigures { p_supply_pa: f64, speeds: [f64; 3] },
    /// The stall torque.
    Stall { p_supply_pa: f64 },
    /// Free speed and the air there (the shaft free).
    Air { p_supply_pa: f64 },
    /// Torque and air at each imposed speed.
    Sweep { p_supply_pa: f64, speeds: Vec<f64> },
    /// Speed and air at each free-shaft point.
    Free { points: Vec<FreePoint> },
}

/// A candidate measurement.
#[derive(Debug, Clone, PartialEq)]
pub struct Candidate {
    /// Its kind.
    pub kind: CandidateKind,
    /// The supply pressure it is measured at, Pa absolute (`None`: a pressure ramp).
    pub at_pa: Option<f64>,
    /// Rig time, hours.
    pub cost_h: f64,
    /// What the technician runs.
    pub rig: RigSettings,
    /// σ of each observable, SI.
    pub sigma: Vec<f64>,
    pub(super) design: Design,
}

impl Candidate {
    /// Its observables for `motor` (NaN where the motor has no steady state there).
    pub(super) fn observe(&self, motor: &Motor, p_atm_pa: f64) -> Vec<f64> {
        let nan = vec![f64::NAN; self.sigma.len()];
        let row = |p: f64| catalogue_row(motor, &Conditions::supplied(p, p_atm_pa), GRID_RAD_S);
        match &self.design {
            Design::KeyFigures {
                p_supply_pa,
                speeds,
            } => {
                let c = Conditions::supplied(*p_supply_pa, p_atm_pa);
                match at_speeds(motor, &c, speeds).as_deref() {
                    Ok([s, m, f]) => {
                        vec![
                            s.torque_nm,
                            m.power_w,
                            m.flow1_kg_s,
                            f.torque_nm,
                            f.flow1_kg_s,
                        ]
                    }
                    _ => nan,
                }
            }
            Design::Stall { p_supply_pa } => {
                row(*p_supply_pa).map_or(nan, |r| vec![r.stall_torque_nm])
            }
            Design::Air { p_supply_pa } => row(*p_supply_pa)
                .map_or(nan, |r| vec![r.free_speed_rad_s, r.air_at_free_speed_kg_s]),
            Design::Sweep {
                p_supply_pa,
                speeds,
            } => {
                let c = Conditions::supplied(*p_supply_pa, p_atm_pa);
                at_speeds(motor, &c, speeds).map_or(nan, |pts| {
                    pts.iter()
                        .flat_map(|p| [p.torque_nm, p.flow1_kg_s])
                        .collect()
                })
            }
            Design::Free { points } => points
                .iter()
                .flat_map(|fp| {
                    free_point(motor, fp, p_atm_pa, fp.omega_guess)
                        .map_or([f64::NAN; 2], |(w, m)| [w, m])
                })
                .collect(),
        }
    }
}

/// The key figures' σ as a page's fit weighs them (docs/formats.md, "Catalogue data"):
/// the reading tolerance times each channel's full scale, the stall torque for both
/// torques, the maximum power, the larger air for both airs.
fn key_sigma(r: &CatalogueRow) -> Vec<f64> {
    let air = r.optimum.flow1_kg_s.max(r.air_at_free_speed_kg_s);
    let full = [
        r.stall_torque_nm,
        r.optimum.power_w,
        air,
        r.stall_torque_nm,
        air,
    ];
    full.iter().map(|v| DEFAULT_TOLERANCE * v.abs()).collect()
}

/// The steady state with the shaft free at `fp`, started at speed `omega`: (ω rad/s, air
/// into port 1 kg/s).
fn free_point(motor: &Motor, fp: &FreePoint, p_atm_pa: f64, omega: f64) -> Option<(f64, f64)> {
    let bc = Boundary {
        c_port2_m3_s_pa: fp.c_outlet_m3_s_pa,
        ..Boundary::supplied(fp.p_supply_pa, p_atm_pa, Load::Torque { t_nm: fp.load_nm })
    };
    let guess: State = [fp.p_supply_pa, p_atm_pa, p_atm_pa, omega];
    let x = steady::free(motor, &bc, &guess).ok()?;
    let w = x[crate::model::motor::idx::OMEGA];
    (w.is_finite() && w > 0.0).then(|| (w, motor.balance(&x, &bc).flow_port1_kg_s))
}

/// `n` values from `a` to `b`, evenly (`log`: evenly in the logarithm).
fn spaced(a: f64, b: f64, n: usize, log: bool) -> Vec<f64> {
    (0..n)
        .map(|i| {
            let t = i as f64 / (n - 1).max(1) as f64;
            if log {
                (a.ln() + t * (b.ln() - a.ln())).exp()
            } else {
                a + t * (b - a)
            }
        })
        .collect()
}

/// The settings of a candidate at one fixed pressure.
fn at_pressure(p: f64, points: usize, readings: usize, records: &'static str) -> RigSettings {
    RigSettings {
        p_supply_pa: [p, p],
        speeds_rad_s: None,
        throttle_m3_s_pa: None,
        load_nm: None,
        points,
        readings,
        duration_s: points as f64 * SECONDS_PER_POINT,
        records,
    }
}

/// Every candidate for the fitted `motor` under `options`: the six kinds measured at one
/// pressure at each asked pressure, and one pressure ramp. The fitted motor's catalogue
/// row at each pressure (`rows`, in the order of `options.pressures_pa`) sets the sweeps'
/// speeds and the load step's torque. Free-shaft points the fitted motor has no steady
/// state at are left out.
pub(super) fn candidates(
    motor: &Motor,
    options: &PlanOptions,
    rows: &[CatalogueRow],
) -> Vec<Candidate> {
    let noise = SensorNoise::typical_for(motor.params().v_disp());
    let rep = (REPEATS as f64).sqrt();
    let mut out = Vec::new();
    let make = |kind, at_pa, rig, sigma, design| Candidate {
        kind,
        at_pa,
        cost_h: options.cost_h(kind),
        rig,
        sigma,
        design,
    };
    for (p, row) in options.pressures_pa.iter().copied().zip(rows) {
        let speeds = [0.0, row.optimum.speed_rad_s, row.free_speed_rad_s];
        let rig = at_pressure(p, 3, 1, "stall torque, maximum power with its speed and air (a speed sweep), free speed and its air, as a page prints them");
        out.push(make(
            CandidateKind::KeyFigures,
            Some(p),
            rig,
            key_sigma(row),
            Design::KeyFigures {
                p_supply_pa: p,
                speeds,
            },
        ));
        let rig = at_pressure(p, 1, REPEATS, "stall torque, brake locked");
        out.push(make(
            CandidateKind::StallTorque,
            Some(p),
            rig,
            vec![noise.torque_nm / rep],
            Design::Stall { p_supply_pa: p },
        ));
        let rig = at_pressure(
            p,
            1,
            REPEATS,
            "free speed and air into port 1 there, shaft free",
        );
        let sigma = vec![noise.speed_rad_s / rep, noise.flow_kg_s / rep];
        out.push(make(
            CandidateKind::AirFlow,
            Some(p),
            rig,
            sigma,
            Design::Air { p_supply_pa: p },
        ));
        let w0 = row.free_speed_rad_s;
        let speeds = spaced(SWEEP_SPAN[0] * w0, SWEEP_SPAN[1] * w0, SWEEP_POINTS, false);
        let mut rig = at_pressure(
            p,
            SWEEP_POINTS,
            1,
            "shaft torque and air into port 1 at each imposed speed",
        );
        rig.speeds_rad_s = Some([speeds[0], speeds[SWEEP_POINTS - 1]]);
        let sigma = [noise.torque_nm, noise.flow_kg_s].repeat(SWEEP_POINTS);
        out.push(make(
            CandidateKind::DatasheetSweep,
            Some(p),
            rig,
            sigma,
            Design::Sweep {
                p_supply_pa: p,
                speeds,
            },
        ));
        out.push(throttle(motor, options, p, row, &noise, &make));
        out.push(load_step(motor, options, p, row, &noise, &make));
    }
    out.push(ramp(motor, options, rows, &noise, &make));
    out.retain(|c| {
        options.weighs(c.kind) && !c.sigma.is_empty() && c.sigma.iter().all(|s| *s > 0.0)
    });
    out
}

/// Free-shaft points solved for the fitted motor in order, each from the last one's speed;
/// those without a steady state are dropped.
fn solved(
    motor: &Motor,
    p_atm_pa: f64,
    start_rad_s: f64,
    points: Vec<FreePoint>,
) -> Vec<FreePoint> {
    let mut omega = start_rad_s;
    points
        .into_iter()
        .filter_map(|mut fp| {
            let (w, _) = free_point(motor, &fp, p_atm_pa, omega)?;
            omega = w;
            fp.omega_guess = w;
            Some(fp)
        })
        .collect()
}

type Make<'a> = dyn Fn(CandidateKind, Option<f64>, RigSettings, Vec<f64>, Design) -> Candidate + 'a;

/// Speed and air at each free-shaft point, σ of the speed and flow sensors.
fn free_sigma(noise: &SensorNoise, n: usize, readings: usize) -> Vec<f64> {
    let r = (readings as f64).sqrt();
    [noise.speed_rad_s / r, noise.flow_kg_s / r].repeat(n)
}

/// The outlet throttle's ramp at `p`, from wide open down (log-spaced conductances).
fn throttle(
    motor: &Motor,
    options: &PlanOptions,
    p: f64,
    row: &CatalogueRow,
    noise: &SensorNoise,
    make: &Make,
) -> Candidate {
    let c = motor.params().c_out2();
    let cs = spaced(
        THROTTLE_SPAN[1] * c,
        THROTTLE_SPAN[0] * c,
        THROTTLE_POINTS,
        true,
    );
    let pts = cs
        .iter()
        .map(|c| FreePoint {
            p_supply_pa: p,
            c_outlet_m3_s_pa: Some(*c),
            load_nm: 0.0,
            omega_guess: 0.0,
        })
        .collect();
    let pts = solved(motor, options.p_atm_pa, row.free_speed_rad_s, pts);
    let mut rig = at_pressure(
        p,
        pts.len(),
        1,
        "shaft speed and air into port 1 at each throttle setting, shaft free",
    );
    rig.throttle_m3_s_pa = pts
        .first()
        .zip(pts.last())
        .and_then(|(a, b)| Some([a.c_outlet_m3_s_pa?, b.c_outlet_m3_s_pa?]));
    let sigma = free_sigma(noise, pts.len(), 1);
    make(
        CandidateKind::OutletThrottleRamp,
        Some(p),
        rig,
        sigma,
        Design::Free { points: pts },
    )
}

/// The load step at `p`: the brake from 0 to [`LOAD_STEP_FRACTION`] of the stall torque.
fn load_step(
    motor: &Motor,
    options: &PlanOptions,
    p: f64,
    row: &CatalogueRow,
    noise: &SensorNoise,
    make: &Make,
) -> Candidate {
    let t = LOAD_STEP_FRACTION * row.stall_torque_nm;
    let pts = [0.0, t]
        .iter()
        .map(|t| FreePoint {
            p_supply_pa: p,
            c_outlet_m3_s_pa: None,
            load_nm: *t,
            omega_guess: 0.0,
        })
        .collect();
    let pts = solved(motor, options.p_atm_pa, row.free_speed_rad_s, pts);
    let mut rig = at_pressure(
        p,
        pts.len(),
        REPEATS,
        "settled shaft speed and air into port 1 before and after the brake's step",
    );
    rig.load_nm = Some([0.0, t]);
    let sigma = free_sigma(noise, pts.len(), REPEATS);
    make(
        CandidateKind::LoadStep,
        Some(p),
        rig,
        sigma,
        Design::Free { points: pts },
    )
}

/// The supply ramp with the shaft free, from half the lowest asked gauge pressure to the
/// highest asked pressure.
fn ramp(
    motor: &Motor,
    options: &PlanOptions,
    rows: &[CatalogueRow],
    noise: &SensorNoise,
    make: &Make,
) -> Candidate {
    let p_atm = options.p_atm_pa;
    let lo_row = options
        .pressures_pa
        .iter()
        .zip(rows)
        .min_by(|a, b| a.0.total_cmp(b.0));
    let hi = options
        .pressures_pa
        .iter()
        .copied()
        .fold(f64::MIN, f64::max);
    let (lo, w_lo) = lo_row.map_or((hi, 0.0), |(p, r)| {
        (p_atm + 0.5 * (p - p_atm), 0.7 * r.free_speed_rad_s)
    });
    let pts = spaced(lo, hi, RAMP_POINTS, false)
        .into_iter()
        .map(|p| FreePoint {
            p_supply_pa: p,
            c_outlet_m3_s_pa: None,
            load_nm: 0.0,
            omega_guess: 0.0,
        })
        .collect();
    let pts = solved(motor, p_atm, w_lo, pts);
    let mut rig = at_pressure(
        lo,
        pts.len(),
        1,
        "shaft speed and air into port 1 against the supply pressure, shaft free",
    );
    rig.p_supply_pa = [lo, hi];
    let sigma = free_sigma(noise, pts.len(), 1);
    make(
        CandidateKind::PressureRamp,
        None,
        rig,
        sigma,
        Design::Free { points: pts },
    )
}
