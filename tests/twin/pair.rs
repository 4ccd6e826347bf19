//! Two motors, one page: what a catalogue page printed at one supply pressure cannot tell.
//!
//! For a motor and its page ([`super::page`]), [`friction_path`] walks the Coulomb friction
//! T_c away from the motor's own value (a 1-D continuation in ln T_c, both ways) and, at
//! each step, re-solves every other parameter a page does not print (the six conductances,
//! the dead volume, the viscous friction d, the expansion ratio ε, the polytropic index n and
//! the critical ratio b; vanes and displacement held) by Levenberg–Marquardt so that each
//! printed number stays inside its rounding interval: the twin prints the SAME page (every key
//! figure, every curve cell, the same curve speeds) for every motor on the path. The path
//! stops where no such motor is found, or where a parameter leaves the twin's own population
//! (more than [`Z_MAX`] spreads from its size-scaled centre, n or b outside their ranges):
//! every motor on the path is one [`super::page::random_motor`] could draw.
//! [`walk_path`] walks any other of those parameters ([`WALKABLE`]) the same way, and
//! [`figure_path`] steers a figure at another pressure itself, re-solving all twelve. A styled
//! page ([`super::styles`]) is read as printed: a table row without curves, a geared page at
//! its output shaft ([`friction_path_geared`]; [`verify_same_styled_page`] prints it again).
//!
//! Along the path the figures at other pressures move: if two motors print the same page and
//! a figure of theirs differs by D (f_b = (1 + D)·f_a), a predictor that sees only the page
//! predicts the same p for both and errs on one of them by at least
//! min_p max(|p/f_a − 1|, |p/f_b − 1|) = D/(2 + D), reached at p = 2·f_a·f_b/(f_a + f_b).
//! (D/(2 + D) ≥ 10 % from D ≥ 22.2 %.)
//!
//! The page's figures are computed here by a solver of its own (the steady pressures at an
//! imposed speed by Newton's method, warm-started along the speed; the free speed as the root
//! of the shaft torque; the max power by golden section), ~100× faster than the twin's
//! reference path in [`super::catalogue`] (pseudo-transient continuation at each point), which
//! [`verify_same_page`] then uses to print both pages and compare them byte for byte.
//! `PAIR_DEBUG=1` prints each step of the continuation to stderr.

use super::catalogue::TwinRow;
use super::motor::{self, TwinMotor, P_ATM_PA};
use super::page::{print_page, PageStyle, FIGURES, SPREAD, V_REF_M3};
use super::rig::{self, Boundary, Port2};
use super::steady::steady_state;
use super::styles::Gear;
use nalgebra::{DMatrix, DVector};
use std::path::Path;

/// Largest distance, in the twin's population spreads ([`SPREAD`]), of a path motor's
/// parameter from its size-scaled centre: 3 (a motor one in ~370 draws of that parameter
/// would reach).
pub const Z_MAX: f64 = 3.0;
/// Step of the continuation in ln T_c.
const STEP: f64 = 0.05;
/// Farthest the continuation goes in ln T_c (×/÷ 4.5).
const S_MAX: f64 = 1.5;
/// Largest printed-value residual accepted, in rounding half-intervals (< 1: inside).
const FEASIBLE: f64 = 0.99;

const RPM: f64 = 30.0 / std::f64::consts::PI;

// ---------------------------------------------------------------------------------------
// Fast steady states

/// The motor at one supply pressure, port 2 open, speed imposed.
struct Bench<'a> {
    m: &'a TwinMotor,
    bc: Boundary,
}

/// Steady pressures, torque and port-1 flow at one speed.
#[derive(Debug, Clone, Copy)]
struct Point {
    p: [f64; 3],
    torque_nm: f64,
    flow_kg_s: f64,
}

impl<'a> Bench<'a> {
    fn new(m: &'a TwinMotor, p_supply_pa: f64) -> Self {
        Bench {
            m,
            bc: Boundary {
                p_port1_pa: p_supply_pa,
                port2: Port2::Open,
                p_atm_pa: P_ATM_PA,
                brake_nm_s_rad: 0.0,
                throttle_b_crit: None,
            },
        }
    }

    /// Net flows into the three volumes at pressures `p` and speed `w`, kg/s.
    fn flows(&self, p: &[f64; 3], w: f64) -> [f64; 3] {
        rig::volume_flows_kg_s(self.m, &self.bc, &[p[0], p[1], p[2], w])
    }

    /// Steady pressures at speed `w` by damped Newton from `warm`; the twin's
    /// pseudo-transient steady state where Newton fails.
    fn pressures(&self, w: f64, warm: [f64; 3]) -> Result<[f64; 3], String> {
        let mut p = warm;
        let norm = |q: &[f64; 3], p: &[f64; 3]| {
            (0..3)
                .map(|i| (q[i] / (self.m.c_in1 * motor::RHO0_KG_M3 * p[i])).abs())
                .fold(0.0, f64::max)
        };
        for _ in 0..60 {
            let q = self.flows(&p, w);
            let r0 = norm(&q, &p);
            let mut jac = nalgebra::Matrix3::zeros();
            for j in 0..3 {
                let h = 1e-7 * p[j];
                let mut pp = p;
                pp[j] += h;
                let qp = self.flows(&pp, w);
                for i in 0..3 {
                    jac[(i, j)] = (qp[i] - q[i]) / h;
                }
            }
            let Some(dp) = jac.lu().solve(&nalgebra::Vector3::new(q[0], q[1], q[2])) else {
                break;
            };
            let mut lambda = 1.0;
            let mut next = p;
            for _ in 0..40 {
                next = std::array::from_fn(|i| (p[i] - lambda * dp[i]).max(0.2 * p[i]));
                if norm(&self.flows(&next, w), &next) < r0 || r0 < 1e-14 {
                    break;
                }
                lambda *= 0.5;
            }
            let small = (0..3).all(|i| (next[i] - p[i]).abs() <= 1e-12 * p[i]);
            p = next;
            if small {
                return Ok(p);
            }
        }
        if norm(&self.flows(&p, w), &p) < 1e-11 {
            return Ok(p);
        }
        let y0 = [self.bc.p_port1_pa, P_ATM_PA, P_ATM_PA, w];
        let y = steady_state(|x| rig::rhs(self.m, &self.bc, x, true), &y0, true)?;
        Ok([y[0], y[1], y[2]])
    }

    /// The point at speed `w` (the datasheet's stall convention at w = 0).
    fn at(&self, w: f64, warm: [f64; 3]) -> Result<Point, String> {
        let p = self.pressures(w, warm)?;
        let torque_nm = if w == 0.0 {
            motor::air_torque_nm(self.m, p, 0.0)
                - motor::static_friction_nm(self.m)
                - motor::law_static_nm(self.m, p)
        } else {
            rig::shaft_torque_nm(self.m, &[p[0], p[1], p[2], w])
        };
        Ok(Point {
            p,
            torque_nm,
            flow_kg_s: rig::flow1_kg_s(self.m, &self.bc, p[0]),
        })
    }

    /// The catalogue row (as [`super::catalogue::catalogue_row`] defines it), from a guess
    /// of the free speed.
    fn row(&self, w_guess: f64) -> Result<TwinRow, String> {
        let start = [self.bc.p_port1_pa, P_ATM_PA, P_ATM_PA];
        let stall = self.at(0.0, start)?;
        // Free speed: bracket the root of the shaft torque, then Illinois regula falsi.
        let mut warm = stall.p;
        let t = |w: f64, warm: &mut [f64; 3]| -> Result<Point, String> {
            let pt = self.at(w, *warm)?;
            *warm = pt.p;
            Ok(pt)
        };
        let (mut a, mut fa) = (0.5 * w_guess, t(0.5 * w_guess, &mut warm)?.torque_nm);
        while fa <= 0.0 {
            a *= 0.5;
            fa = t(a, &mut warm)?.torque_nm;
            if a < 1e-3 {
                return Err("pair: the motor does not turn".into());
            }
        }
        let (mut b, mut fb) = (1.5 * w_guess, t(1.5 * w_guess, &mut warm)?.torque_nm);
        while fb >= 0.0 {
            b *= 1.5;
            fb = t(b, &mut warm)?.torque_nm;
        }
        let mut side = 0;
        let mut free = t(a, &mut warm)?;
        let mut w_free = a;
        for _ in 0..200 {
            let c = (a * fb - b * fa) / (fb - fa);
            let pt = t(c, &mut warm)?;
            w_free = c;
            free = pt;
            if pt.torque_nm == 0.0 || (b - a) < 1e-12 * b {
                break;
            }
            if (pt.torque_nm > 0.0) == (fa > 0.0) {
                a = c;
                fa = pt.torque_nm;
                if side == -1 {
                    fb *= 0.5;
                }
                side = -1;
            } else {
                b = c;
                fb = pt.torque_nm;
                if side == 1 {
                    fa *= 0.5;
                }
                side = 1;
            }
            if (pt.torque_nm / stall.torque_nm).abs() < 1e-13 {
                break;
            }
        }
        // Max power: a scan of 20 intervals, then golden section around the best.
        let n = 20;
        let mut warm = stall.p;
        let mut best = (1, f64::NEG_INFINITY);
        for k in 1..n {
            let w = w_free * k as f64 / n as f64;
            let pt = t(w, &mut warm)?;
            if pt.torque_nm * w > best.1 {
                best = (k, pt.torque_nm * w);
            }
        }
        let (mut lo, mut hi) = (
            w_free * (best.0 - 1) as f64 / n as f64,
            w_free * (best.0 + 1) as f64 / n as f64,
        );
        let g = (5f64.sqrt() - 1.0) / 2.0;
        let mut warm = stall.p;
        let mut power = |w: f64| t(w, &mut warm).map(|pt| pt.torque_nm * w);
        let (mut x1, mut x2) = (hi - g * (hi - lo), lo + g * (hi - lo));
        let (mut p1, mut p2) = (power(x1)?, power(x2)?);
        while hi - lo > 1e-8 * w_free {
            if p1 > p2 {
                hi = x2;
                (x2, p2) = (x1, p1);
                x1 = hi - g * (hi - lo);
                p1 = power(x1)?;
            } else {
                lo = x1;
                (x1, p1) = (x2, p2);
                x2 = lo + g * (hi - lo);
                p2 = power(x2)?;
            }
        }
        let w_max = 0.5 * (lo + hi);
        let at_max = t(w_max, &mut warm)?;
        Ok(TwinRow {
            free_speed_rad_s: w_free,
            max_power_w: at_max.torque_nm * w_max,
            speed_at_max_power_rad_s: w_max,
            torque_at_max_power_nm: at_max.torque_nm,
            stall_torque_nm: stall.torque_nm,
            air_at_max_power_kg_s: at_max.flow_kg_s,
            air_at_free_speed_kg_s: free.flow_kg_s,
        })
    }
}

/// The catalogue row of `m` at `bar_g` by the fast solver (free speed guessed `w_guess`).
pub fn fast_row(m: &TwinMotor, bar_g: f64, w_guess: f64) -> Result<TwinRow, String> {
    Bench::new(m, P_ATM_PA + bar_g * 1e5).row(w_guess)
}

// ---------------------------------------------------------------------------------------
// The printed page as intervals

/// What a printed number is.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Printed {
    /// Key figure k of [`FIGURES`].
    Figure(usize),
    /// A curve cell at a speed (rad/s): column 0 torque, 1 power, 2 air.
    Cell(f64, usize),
    /// The free speed's range that keeps the curve file's speeds (step and rows).
    Grid,
    /// Key figure k of [`FIGURES`] at another supply pressure (bar g): a second measurement
    /// added to the page ([`extra_items`]).
    Extra(usize, f64),
}

/// A number of the page: what it is, its factor from SI to the page's unit, and the interval
/// [lo, hi] (page unit) inside which the twin prints the same text.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Item {
    /// What it is.
    pub what: Printed,
    /// Page unit per SI unit.
    pub per_si: f64,
    /// Interval, page units.
    pub lo: f64,
    /// Interval, page units.
    pub hi: f64,
}

/// Half a unit of the last of 3 significant digits of the printed text `s`.
fn half_unit(s: &str) -> f64 {
    let v: f64 = s.parse().unwrap();
    let mag = v.abs().log10().floor() as i32;
    0.5 * 10f64.powi(mag - 2)
}

/// The numbers of the page printed in `dir` (rig.toml and curves.csv as
/// [`super::page::print_page`] writes them) for `style`, with the free speed `w_free` of the
/// motor that printed it.
pub fn page_items(dir: &Path, style: &PageStyle, w_free: f64) -> Result<Vec<Item>, String> {
    let [speed, torque, power, air] = style.units;
    let fig_units = [speed, power, speed, torque, torque, air, air];
    let toml = std::fs::read_to_string(dir.join("rig.toml")).map_err(|e| e.to_string())?;
    let mut items = Vec::new();
    for line in toml.lines() {
        let Some((key, rest)) = line.split_once(" = \"") else {
            continue;
        };
        let Some(k) = FIGURES.iter().position(|f| *f == key) else {
            continue;
        };
        let text = rest.split_whitespace().next().ok_or("figure")?;
        let v: f64 = text.parse().map_err(|_| format!("figure {text}"))?;
        let h = half_unit(text);
        items.push(Item {
            what: Printed::Figure(k),
            per_si: fig_units[k].per_si,
            lo: v - h,
            hi: v + h,
        });
    }
    let Ok(csv) = std::fs::read_to_string(dir.join("curves.csv")) else {
        return Ok(items);
    };
    let rows: Vec<Vec<&str>> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    for row in &rows {
        let w = row[0].parse::<f64>().map_err(|e| e.to_string())? / RPM;
        for (j, unit) in [torque, power, air].iter().enumerate() {
            let cell = row[j + 1];
            if cell.is_empty() {
                continue;
            }
            let v: f64 = cell
                .parse()
                .map_err(|e: std::num::ParseFloatError| e.to_string())?;
            let h = half_unit(cell);
            items.push(Item {
                what: Printed::Cell(w, j),
                per_si: unit.per_si,
                lo: v - h,
                hi: v + h,
            });
        }
    }
    // The speeds of the rows: step = the first of 1, 2, 2.5, 5, 10 × 10ⁿ rpm at or above
    // free/(n + 0.5), rows k·step while k·step < 0.97·free. Keeping both keeps the speeds.
    let n = style.curve_points as f64 + 0.5;
    let free_rpm = w_free * RPM;
    let raw = free_rpm / n;
    let decade = 10f64.powf(raw.log10().floor());
    let ladder = [0.5, 1.0, 2.0, 2.5, 5.0, 10.0].map(|k| k * decade);
    let i = ladder[1..].iter().position(|s| *s >= raw).unwrap() + 1;
    let step = ladder[i];
    let k_rows = rows.len() as f64;
    let lo = (ladder[i - 1] * n).max((k_rows - 1.0) * step / 0.97);
    let hi = (step * n).min(k_rows * step / 0.97);
    items.push(Item {
        what: Printed::Grid,
        per_si: RPM,
        lo,
        hi,
    });
    Ok(items)
}

/// Items for figures of `m` at other supply pressures, `(figure k, bar g)`, printed in SI to
/// 3 significant digits: a second measurement added to a page.
pub fn extra_items(m: &TwinMotor, extra: &[(usize, f64)]) -> Result<Vec<Item>, String> {
    extra_items_at(m, None, extra)
}

/// [`extra_items`] at the output shaft of `gear` (the motor's shaft with `None`).
fn extra_items_at(
    m: &TwinMotor,
    gear: Option<Gear>,
    extra: &[(usize, f64)],
) -> Result<Vec<Item>, String> {
    extra
        .iter()
        .map(|&(k, bar_g)| {
            let v = super::page::row_values(&at_shaft(gear, &fast_row(m, bar_g, 500.0)?))[k];
            let text = super::page::significant(v, 3);
            let (v, h) = (text.parse::<f64>().unwrap(), half_unit(&text));
            Ok(Item {
                what: Printed::Extra(k, bar_g),
                per_si: 1.0,
                lo: v - h,
                hi: v + h,
            })
        })
        .collect()
}

/// A motor-shaft row at the output shaft of `gear` ([`Gear::output_row`]; itself with `None`).
fn at_shaft(gear: Option<Gear>, row: &TwinRow) -> TwinRow {
    gear.map_or(*row, |g| g.output_row(row))
}

/// Values of the page's items for motor `m` at `bar_g`, in page units, at the output shaft of
/// `gear` (a geared page: speeds ω/G, torques η·G·T, power η·P), and its motor-shaft row.
fn page_values(
    m: &TwinMotor,
    gear: Option<Gear>,
    bar_g: f64,
    items: &[Item],
    w_guess: f64,
) -> Result<(Vec<f64>, TwinRow), String> {
    let bench = Bench::new(m, P_ATM_PA + bar_g * 1e5);
    let row = bench.row(w_guess)?;
    let out = at_shaft(gear, &row);
    let figs = super::page::row_values(&out);
    let (g, eta) = gear.map_or((1.0, 1.0), |g| (g.ratio, g.efficiency));
    let mut warm = [bench.bc.p_port1_pa, P_ATM_PA, P_ATM_PA];
    let mut cache: Vec<(f64, Point)> = Vec::new();
    let mut values = Vec::with_capacity(items.len());
    let mut other: Vec<(f64, [f64; 7])> = Vec::new();
    for it in items {
        let si = match it.what {
            Printed::Figure(k) => figs[k],
            Printed::Extra(k, b) => match other.iter().find(|(x, _)| *x == b) {
                Some((_, f)) => f[k],
                None => {
                    let r = fast_row(m, b, row.free_speed_rad_s)?;
                    let f = super::page::row_values(&at_shaft(gear, &r));
                    other.push((b, f));
                    f[k]
                }
            },
            Printed::Grid => out.free_speed_rad_s,
            Printed::Cell(w, j) => {
                let pt = match cache.iter().find(|(x, _)| *x == w) {
                    Some((_, pt)) => *pt,
                    None => {
                        let pt = bench.at(w * g, warm)?;
                        warm = pt.p;
                        cache.push((w, pt));
                        pt
                    }
                };
                [
                    eta * g * pt.torque_nm,
                    eta * pt.torque_nm * w * g,
                    pt.flow_kg_s,
                ][j]
            }
        };
        values.push(si * it.per_si);
    }
    Ok((values, row))
}

/// Share of its rounding interval a figure at max power may use (the speed, torque and air
/// there): the reference printer finds that speed on a flat maximum by golden section on
/// steady states of residual 1e-7, which places it within a few 1e-5 of itself; kept this far
/// from the interval's ends, the reference prints the same digits.
const AT_MAX_POWER_SHARE: f64 = 0.9;

/// Residuals of the items in half-intervals: 0 at the interval's centre, ±1 at its ends
/// (±1 at [`AT_MAX_POWER_SHARE`] of the half-interval for the figures at max power).
fn residuals(items: &[Item], values: &[f64]) -> Vec<f64> {
    items
        .iter()
        .zip(values)
        .map(|(it, v)| {
            let share = match it.what {
                Printed::Figure(2 | 3 | 5) | Printed::Extra(2 | 3 | 5, _) => AT_MAX_POWER_SHARE,
                _ => 1.0,
            };
            (v - 0.5 * (it.lo + it.hi)) / (0.5 * (it.hi - it.lo) * share)
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// The parameters a page does not print, and the population they come from

/// Number of re-solved parameters.
const NP: usize = 11;
/// Their names, in the order of `to_x`.
pub const FREE: [&str; NP] = [
    "c_in1", "c_out2", "c_ext", "c_1e", "c_2e", "c_12", "v_dead", "visc", "eps", "n_poly", "b_crit",
];

/// x in (lo, hi) as an unconstrained coordinate, ln((x − lo)/(hi − x)).
fn logit(v: f64, r: (f64, f64)) -> f64 {
    ((v - r.0) / (r.1 - v)).ln()
}

/// The inverse of [`logit`].
fn expit(x: f64, r: (f64, f64)) -> f64 {
    r.0 + (r.1 - r.0) / (1.0 + (-x).exp())
}

/// The re-solved parameters as unconstrained coordinates: ln of each, ln(ε − 1), and n
/// and b mapped from their population ranges by [`logit`] (so that they stay inside).
fn to_x(m: &TwinMotor) -> [f64; NP] {
    [
        m.c_in1.ln(),
        m.c_out2.ln(),
        m.c_ext.ln(),
        m.c_1e.ln(),
        m.c_2e.ln(),
        m.c_12.ln(),
        m.v_dead.ln(),
        m.visc.ln(),
        (m.eps - 1.0).ln(),
        logit(m.n_poly, SPREAD.n_poly),
        logit(m.b_crit, SPREAD.b_crit),
    ]
}

/// The parameters a path may walk: [`FREE`], then `t_coulomb` (index `NP`).
pub const WALKABLE: [&str; NP + 1] = [
    "c_in1",
    "c_out2",
    "c_ext",
    "c_1e",
    "c_2e",
    "c_12",
    "v_dead",
    "visc",
    "eps",
    "n_poly",
    "b_crit",
    "t_coulomb",
];

/// The population spread of each coordinate of [`WALKABLE`] (ln for the positive ones, the
/// logit's unit for n and b): the scale of the pull toward the page's motor.
const SIGMA: [f64; NP + 1] = [
    0.35, 0.35, 0.35, 0.35, 0.35, 0.35, 0.4, 0.5, 0.5, 1.0, 1.0, 0.5,
];

/// Every coordinate of [`WALKABLE`]: [`to_x`] and ln T_c.
fn all_coords(m: &TwinMotor) -> [f64; NP + 1] {
    let x = to_x(m);
    std::array::from_fn(|i| if i < NP { x[i] } else { m.t_coulomb.ln() })
}

/// `y` without its coordinate `j`: the re-solved ones of a path that walks `j`.
fn rest(j: usize, y: &[f64; NP + 1]) -> [f64; NP] {
    std::array::from_fn(|i| if i < j { y[i] } else { y[i + 1] })
}

/// The motor whose coordinate `j` is `v` and whose others are `x` (in [`WALKABLE`] order
/// without `j`).
fn motor_at(base: &TwinMotor, j: usize, x: &[f64], v: f64) -> TwinMotor {
    let y: [f64; NP + 1] = std::array::from_fn(|i| match i.cmp(&j) {
        std::cmp::Ordering::Less => x[i],
        std::cmp::Ordering::Equal => v,
        std::cmp::Ordering::Greater => x[i - 1],
    });
    from_x(base, &y[..NP], y[NP])
}

fn from_x(base: &TwinMotor, x: &[f64], ln_tc: f64) -> TwinMotor {
    TwinMotor {
        c_in1: x[0].exp(),
        c_out2: x[1].exp(),
        c_ext: x[2].exp(),
        c_1e: x[3].exp(),
        c_2e: x[4].exp(),
        c_12: x[5].exp(),
        v_dead: x[6].exp(),
        visc: x[7].exp(),
        eps: 1.0 + x[8].exp(),
        n_poly: expit(x[9], SPREAD.n_poly),
        b_crit: expit(x[10], SPREAD.b_crit),
        t_coulomb: ln_tc.exp(),
        ..base.clone()
    }
}

/// Distance of each parameter of `m` from its size-scaled centre in the twin's population,
/// in spreads ([`super::page::random_motor`]); n and b: 0 inside their ranges, else 99.
/// Order: [`FREE`], then T_c.
pub fn population_z(m: &TwinMotor) -> [f64; NP + 1] {
    let s = m.v_disp / V_REF_M3;
    let area = s.powf(2.0 / 3.0);
    let sp = SPREAD;
    let z = |v: f64, centre: f64, sigma: f64| (v / centre).ln() / sigma;
    let inside = |v: f64, r: (f64, f64)| if v >= r.0 && v <= r.1 { 0.0 } else { 99.0 };
    [
        z(m.c_in1, 6.758e-9 * area, sp.conductance),
        z(m.c_out2, 6.758e-9 * area, sp.conductance),
        z(m.c_ext, 1.171e-8 * area, sp.conductance),
        z(m.c_1e, 2.078e-9 * area, sp.conductance),
        z(m.c_2e, 2.078e-9 * area, sp.conductance),
        z(m.c_12, 7.62e-10 * area, sp.conductance),
        z(m.v_dead, 0.1e-6 * s, sp.dead_volume),
        z(m.visc, 6e-5 * s.powf(4.0 / 3.0), sp.friction),
        z(m.eps - 1.0, 0.071, sp.expansion),
        inside(m.n_poly, sp.n_poly),
        inside(m.b_crit, sp.b_crit),
        z(m.t_coulomb, 0.02 * s, sp.friction),
    ]
}

/// Largest |z| of [`population_z`].
pub fn population_distance(m: &TwinMotor) -> f64 {
    population_z(m).iter().fold(0.0, |a, z| a.max(z.abs()))
}

// ---------------------------------------------------------------------------------------
// The continuation

/// A motor on the path: its ln T_c offset from the page's motor, the motor, its largest
/// printed-value residual (< 1: it prints the same page) and its rows at the pressures asked.
#[derive(Debug, Clone)]
pub struct PathPoint {
    /// ln(T_c / T_c of the page's motor).
    pub s: f64,
    /// The motor.
    pub motor: TwinMotor,
    /// Largest |residual| of the printed numbers, in rounding half-intervals.
    pub worst_residual: f64,
    /// Rows at the pressures of [`friction_path`]'s `bar_g`.
    pub rows: Vec<TwinRow>,
}

/// Weight of the pull toward the page motor's parameters in the least-squares problem
/// (per population spread): small, so that it only picks one motor where the page leaves a
/// direction free.
const PULL: f64 = 0.02;

/// Sharpened residual: r for |r| ≤ 0.7, growing as r⁵ beyond, so that least squares keeps
/// every printed number inside its interval rather than the sum small.
fn sharp(r: f64) -> f64 {
    r * (1.0 + (r / 0.7).powi(8)).sqrt()
}

/// Least-squares residual vector at x for fixed ln T_c.
#[allow(clippy::too_many_arguments)]
fn objective(
    base: &TwinMotor,
    gear: Option<Gear>,
    items: &[Item],
    supply_bar_g: f64,
    x: &[f64],
    x0: &[f64; NP],
    walk: (usize, f64),
    w_guess: f64,
) -> Option<(Vec<f64>, f64)> {
    let m = motor_at(base, walk.0, x, walk.1);
    let (values, _) = page_values(&m, gear, supply_bar_g, items, w_guess).ok()?;
    let r = residuals(items, &values);
    let worst = r.iter().fold(0.0f64, |a, r| a.max(r.abs()));
    let sigma = rest(walk.0, &SIGMA);
    let mut out: Vec<f64> = r.into_iter().map(sharp).collect();
    out.extend((0..NP).map(|i| PULL * (x[i] - x0[i]) / sigma[i]));
    Some((out, worst))
}

/// Levenberg–Marquardt on [`objective`] from `x`; returns the best x and its worst residual.
#[allow(clippy::too_many_arguments)]
fn solve(
    base: &TwinMotor,
    gear: Option<Gear>,
    items: &[Item],
    supply_bar_g: f64,
    x: [f64; NP],
    x0: &[f64; NP],
    walk: (usize, f64),
    w_guess: f64,
) -> Option<([f64; NP], f64)> {
    levenberg_marquardt(
        |x: &[f64]| objective(base, gear, items, supply_bar_g, x, x0, walk, w_guess),
        x,
    )
}

/// Levenberg–Marquardt on the residuals `f` (with the worst printed-value residual beside
/// them) from `x`, until that worst residual is below 0.5 or no step lowers the sum of
/// squares; returns the last x and its worst residual.
fn levenberg_marquardt<const N: usize>(
    f: impl Fn(&[f64]) -> Option<(Vec<f64>, f64)>,
    x: [f64; N],
) -> Option<([f64; N], f64)> {
    let (mut r, mut worst) = f(&x)?;
    let mut x = x;
    let mut mu = 1e-3;
    let cost = |r: &[f64]| r.iter().map(|v| v * v).sum::<f64>();
    for _ in 0..30 {
        if worst < 0.5 {
            break;
        }
        let n = r.len();
        let mut jac = DMatrix::zeros(n, N);
        for j in 0..N {
            let mut xp = x;
            xp[j] += 1e-6;
            let (rp, _) = f(&xp)?;
            for i in 0..n {
                jac[(i, j)] = (rp[i] - r[i]) / 1e-6;
            }
        }
        let jt = jac.transpose();
        let g = &jt * DVector::from_column_slice(&r);
        let h = &jt * &jac;
        let mut improved = false;
        for _ in 0..8 {
            let mut a = h.clone();
            for i in 0..N {
                a[(i, i)] += mu * (h[(i, i)] + 1e-12);
            }
            let Some(dx) = a.lu().solve(&g) else {
                mu *= 10.0;
                continue;
            };
            let xn: [f64; N] = std::array::from_fn(|i| x[i] - dx[i].clamp(-0.3, 0.3));
            if let Some((rn, wn)) = f(&xn) {
                if cost(&rn) < cost(&r) {
                    (x, r, worst) = (xn, rn, wn);
                    mu = (mu * 0.3).max(1e-9);
                    improved = true;
                    break;
                }
            }
            mu *= 10.0;
        }
        if !improved {
            break;
        }
    }
    Some((x, worst))
}

/// Motors printing the same page as `m` (printed in `page_dir` in `style`, with the
/// figures `extra` of [`extra_items`] beside it), from T_c·e^s for s walking from 0 up and
/// down in steps of 0.05 until no motor of the twin's population prints that page; each
/// with its rows at `bar_g`. Sorted by s.
pub fn friction_path(
    m: &TwinMotor,
    style: &PageStyle,
    page_dir: &Path,
    extra: &[(usize, f64)],
    bar_g: &[f64],
) -> Result<Vec<PathPoint>, String> {
    friction_path_geared(m, None, style, page_dir, extra, bar_g)
}

/// [`friction_path`] of a page printed at the output shaft of `gear` (a geared motor's page,
/// [`super::styles`]; the gearbox held along the path). The rows of the path stay the motor
/// shaft's: a spread, a ratio, is the same at either shaft.
pub fn friction_path_geared(
    m: &TwinMotor,
    gear: Option<Gear>,
    style: &PageStyle,
    page_dir: &Path,
    extra: &[(usize, f64)],
    bar_g: &[f64],
) -> Result<Vec<PathPoint>, String> {
    walk_path(m, gear, style, page_dir, extra, bar_g, NP)
}

/// [`friction_path_geared`] walking parameter `j` of [`WALKABLE`] (its coordinate: ln of a
/// positive parameter, ln(ε − 1), the logit of n or b over their ranges) instead of T_c,
/// every other one re-solved; `s` of each point is its offset in that coordinate.
pub fn walk_path(
    m: &TwinMotor,
    gear: Option<Gear>,
    style: &PageStyle,
    page_dir: &Path,
    extra: &[(usize, f64)],
    bar_g: &[f64],
    j: usize,
) -> Result<Vec<PathPoint>, String> {
    let supply = style.supply.1;
    let row0 = fast_row(m, supply, 500.0)?;
    let w_free_out = at_shaft(gear, &row0).free_speed_rad_s;
    let mut items = page_items(page_dir, style, w_free_out)?;
    items.extend(extra_items_at(m, gear, extra)?);
    let y0 = all_coords(m);
    let (x0, v0) = (rest(j, &y0), y0[j]);
    let rows_at = |mm: &TwinMotor, w_guess: f64| -> Result<Vec<TwinRow>, String> {
        bar_g.iter().map(|b| fast_row(mm, *b, w_guess)).collect()
    };
    let (values0, _) = page_values(m, gear, supply, &items, row0.free_speed_rad_s)?;
    let worst0 = residuals(&items, &values0)
        .iter()
        .fold(0.0f64, |a, r| a.max(r.abs()));
    let mut path = vec![PathPoint {
        s: 0.0,
        motor: m.clone(),
        worst_residual: worst0,
        rows: rows_at(m, row0.free_speed_rad_s)?,
    }];
    for dir in [1.0, -1.0] {
        let (mut s, mut x): (f64, [f64; NP]) = (0.0, x0);
        // dx/ds from the last two path motors: the start of the next solve.
        let mut slope = [0.0; NP];
        let mut step = STEP;
        while s.abs() < S_MAX && step >= STEP / 16.0 {
            let s_try = s + dir * step;
            let guess: [f64; NP] = std::array::from_fn(|i| x[i] + slope[i] * (s_try - s));
            let found = solve(
                m,
                gear,
                &items,
                supply,
                guess,
                &x0,
                (j, v0 + s_try),
                row0.free_speed_rad_s,
            );
            let ok = found.and_then(|(xn, worst)| {
                let mm = motor_at(m, j, &xn, v0 + s_try);
                if std::env::var_os("PAIR_DEBUG").is_some() {
                    eprintln!(
                        "s {s_try:+.4} worst {worst:.3} z {:.2} {:?}",
                        population_distance(&mm),
                        population_z(&mm)
                    );
                }
                (worst < FEASIBLE && population_distance(&mm) <= Z_MAX).then_some((xn, worst, mm))
            });
            match ok {
                Some((xn, worst, mm)) => {
                    let rows = rows_at(&mm, row0.free_speed_rad_s)?;
                    path.push(PathPoint {
                        s: s_try,
                        motor: mm,
                        worst_residual: worst,
                        rows,
                    });
                    slope = std::array::from_fn(|i| (xn[i] - x[i]) / (s_try - s));
                    (s, x) = (s_try, xn);
                    step = (2.0 * step).min(STEP);
                }
                None => step *= 0.5,
            }
        }
    }
    path.sort_by(|a, b| a.s.total_cmp(&b.s));
    Ok(path)
}

/// The largest residual, in rounding half-intervals, of the page printed in `page_dir` in
/// `style` (at the output shaft of `gear`) against motor `m`'s own numbers: below 1 where
/// `m` prints that page digit for digit.
pub fn page_residual(
    m: &TwinMotor,
    gear: Option<Gear>,
    style: &PageStyle,
    page_dir: &Path,
) -> Result<f64, String> {
    let row0 = fast_row(m, style.supply.1, 500.0)?;
    let items = page_items(page_dir, style, at_shaft(gear, &row0).free_speed_rad_s)?;
    let (values, _) = page_values(m, gear, style.supply.1, &items, row0.free_speed_rad_s)?;
    Ok(residuals(&items, &values)
        .iter()
        .fold(0.0f64, |a, r| a.max(r.abs())))
}

/// Tolerance of the figure a [`figure_path`] steers, in ln: the target is met within it.
const TARGET_TOL: f64 = 0.004;

/// Motors printing the same page as `m` whose figure `target.0` of [`FIGURES`] at
/// `target.1` bar g is steered up and down: a continuation in s = ln(f/f₀) in steps of
/// 0.02, every coordinate of [`WALKABLE`] re-solved at each step so that the page stays
/// printed digit for digit and ln f = ln f₀ + s within `TARGET_TOL`; it stops where no
/// motor of the twin's population does both. The widest pair the page allows in that
/// figure, as far as a local search finds it (a walk of one parameter, [`walk_path`], only
/// sees the figure move as that parameter does). Rows at `bar_g` as in [`friction_path`].
pub fn figure_path(
    m: &TwinMotor,
    gear: Option<Gear>,
    style: &PageStyle,
    page_dir: &Path,
    bar_g: &[f64],
    target: (usize, f64),
) -> Result<Vec<PathPoint>, String> {
    let supply = style.supply.1;
    let row0 = fast_row(m, supply, 500.0)?;
    let w0 = row0.free_speed_rad_s;
    let items = page_items(page_dir, style, at_shaft(gear, &row0).free_speed_rad_s)?;
    let y0 = all_coords(m);
    let f0 = super::page::row_values(&fast_row(m, target.1, w0)?)[target.0].ln();
    let rows_at = |mm: &TwinMotor| -> Result<Vec<TwinRow>, String> {
        bar_g.iter().map(|b| fast_row(mm, *b, w0)).collect()
    };
    let motor_of = |y: &[f64]| from_x(m, &y[..NP], y[NP]);
    // The page's residuals, the figure's (in TARGET_TOL), and the pull toward the page's
    // motor; the worst of the first two.
    let objective = |y: &[f64], s: f64| -> Option<(Vec<f64>, f64)> {
        let mm = motor_of(y);
        let (values, _) = page_values(&mm, gear, supply, &items, w0).ok()?;
        let mut r = residuals(&items, &values);
        let f = super::page::row_values(&fast_row(&mm, target.1, w0).ok()?)[target.0];
        r.push((f.ln() - f0 - s) / TARGET_TOL);
        let worst = r.iter().fold(0.0f64, |a, r| a.max(r.abs()));
        let mut out: Vec<f64> = r.into_iter().map(sharp).collect();
        out.extend((0..=NP).map(|i| PULL * (y[i] - y0[i]) / SIGMA[i]));
        Some((out, worst))
    };
    let (values0, _) = page_values(m, gear, supply, &items, w0)?;
    let worst0 = residuals(&items, &values0)
        .iter()
        .fold(0.0f64, |a, r| a.max(r.abs()));
    let mut path = vec![PathPoint {
        s: 0.0,
        motor: m.clone(),
        worst_residual: worst0,
        rows: rows_at(m)?,
    }];
    let step0 = 0.02;
    for dir in [1.0, -1.0] {
        let (mut s, mut y): (f64, _) = (0.0, y0);
        let mut slope = [0.0; NP + 1];
        let mut step = step0;
        while s.abs() < 0.7 && step >= step0 / 16.0 {
            let s_try = s + dir * step;
            let guess: [f64; NP + 1] = std::array::from_fn(|i| y[i] + slope[i] * (s_try - s));
            let ok = levenberg_marquardt(|y: &[f64]| objective(y, s_try), guess).and_then(
                |(yn, worst)| {
                    let mm = motor_of(&yn);
                    (worst < FEASIBLE && population_distance(&mm) <= Z_MAX)
                        .then_some((yn, worst, mm))
                },
            );
            match ok {
                Some((yn, worst, mm)) => {
                    path.push(PathPoint {
                        s: s_try,
                        rows: rows_at(&mm)?,
                        motor: mm,
                        worst_residual: worst,
                    });
                    slope = std::array::from_fn(|i| (yn[i] - y[i]) / (s_try - s));
                    (s, y) = (s_try, yn);
                    step = (2.0 * step).min(step0);
                }
                None => step *= 0.5,
            }
        }
    }
    path.sort_by(|a, b| a.s.total_cmp(&b.s));
    Ok(path)
}

/// Spread of figure `k` at pressure index `p` over the path: (max/min − 1, index of the
/// smallest, index of the largest).
pub fn spread(path: &[PathPoint], p: usize, k: usize) -> (f64, usize, usize) {
    let v: Vec<f64> = path
        .iter()
        .map(|pt| super::page::row_values(&pt.rows[p])[k])
        .collect();
    let (mut lo, mut hi) = (0, 0);
    for i in 0..v.len() {
        if v[i] < v[lo] {
            lo = i;
        }
        if v[i] > v[hi] {
            hi = i;
        }
    }
    (v[hi] / v[lo] - 1.0, lo, hi)
}

/// Least worst error any predictor that sees only the page can have on a pair whose figure
/// differs by `d` (f_b = (1 + d)·f_a): d/(2 + d).
pub fn forced_error(d: f64) -> f64 {
    d / (2.0 + d)
}

/// Prints the styled pages of `a` and `b` ([`super::styles::print_styled_page`], the twin's
/// reference printer) into `dir`/a and `dir`/b and returns whether every file is byte for
/// byte the same.
pub fn verify_same_styled_page(
    a: &TwinMotor,
    b: &TwinMotor,
    page: &super::styles::StyledPage,
    dir: &Path,
) -> Result<bool, String> {
    let (da, db) = (dir.join("a"), dir.join("b"));
    super::styles::print_styled_page(&da, a, page)?;
    super::styles::print_styled_page(&db, b, page)?;
    let read = |d: &Path, f: &str| std::fs::read(d.join(f)).ok();
    Ok(["rig.toml", "curves.csv"]
        .iter()
        .all(|f| read(&da, f) == read(&db, f)))
}

/// Prints the pages of `a` and `b` in `style` with the twin's reference printer
/// ([`print_page`], its pseudo-transient steady states) into `dir`/a and `dir`/b and
/// returns whether every file is byte for byte the same.
pub fn verify_same_page(
    a: &TwinMotor,
    b: &TwinMotor,
    style: &PageStyle,
    dir: &Path,
) -> Result<bool, String> {
    let (da, db) = (dir.join("a"), dir.join("b"));
    for d in [&da, &db] {
        std::fs::create_dir_all(d).map_err(|e| e.to_string())?;
    }
    print_page(&da, a, style)?;
    print_page(&db, b, style)?;
    let read = |d: &Path, f: &str| std::fs::read(d.join(f)).ok();
    Ok(["rig.toml", "curves.csv"]
        .iter()
        .all(|f| read(&da, f) == read(&db, f)))
}
