//! A new motor from its catalogue page, judged on pages vanefit did not make: the twin
//! (tests/twin/page.rs) prints the page of a random motor of 1.5–15 cm³ as a maker would,
//! `vanefit fit` (default options) then `vanefit predict --pressures 3,4,5,6,7 --unit bar_g`
//! run on it, and the predicted figures, correction factors and their 95 % bands are compared
//! with the twin's own figures at 3–7 bar g.
//!
//! Over many motors: how many bands hold the truth (per figure, per pressure, per factor),
//! the median band half-width relative to the value, and the worst error of the point
//! prediction. The long table is an ignored test; the CI version runs a few motors.

use crate::twin;

use rayon::prelude::*;
use std::path::Path;
use std::process::Command;
use twin::page::{page_style, print_page, random_motor, row_values, truth, FIGURES, SPREAD};
use twin::page::{AIR_UNITS, POWER_UNITS, SPEED_UNITS, TORQUE_UNITS};

/// Pressures of the prediction, bar g.
pub(crate) const BAR_G: [f64; 5] = [3.0, 4.0, 5.0, 6.0, 7.0];
/// Reference pressure of the correction factors, bar g (vanefit's default).
const REFERENCE_BAR_G: f64 = 6.3;
/// vanefit's catalogue.csv columns in [`FIGURES`] order, with their value per SI unit.
pub(crate) const COLUMNS: [(&str, f64); 7] = [
    ("free_speed_rpm", 30.0 / std::f64::consts::PI),
    ("max_power_w", 1.0),
    ("speed_at_max_power_rpm", 30.0 / std::f64::consts::PI),
    ("torque_at_max_power_nm", 1.0),
    ("stall_torque_nm", 1.0),
    ("air_at_max_power_l_s_anr", 1.0 / (1e-3 * 1.185)),
    ("air_at_free_speed_l_s_anr", 1.0 / (1e-3 * 1.185)),
];
/// vanefit's factors.csv columns.
const FACTORS: [&str; 4] = ["power", "speed", "torque", "air"];

/// A predicted value, its band (`None` where vanefit printed none) and the truth.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Check {
    pub(crate) value: f64,
    pub(crate) band: Option<(f64, f64)>,
    pub(crate) truth: f64,
}

impl Check {
    pub(crate) fn holds(&self) -> bool {
        self.band
            .is_some_and(|(lo, hi)| lo <= self.truth && self.truth <= hi)
    }
    /// Half the band's width relative to the value (0 without a band).
    pub(crate) fn half_width(&self) -> f64 {
        self.band
            .map_or(0.0, |(lo, hi)| 0.5 * (hi - lo) / self.value.abs())
    }
    /// Relative error of the point prediction.
    pub(crate) fn error(&self) -> f64 {
        self.value / self.truth - 1.0
    }
    /// Relative error of the band's geometric centre √(lo·hi): with bands from posterior
    /// samples, the posterior median of a figure whose posterior is log-normal (an
    /// alternative point predictor to the figure at the fit's optimum). The value itself
    /// where there is no band.
    fn centre_error(&self) -> f64 {
        self.band
            .filter(|(lo, hi)| *lo > 0.0 && *hi > 0.0)
            .map_or(self.value, |(lo, hi)| (lo * hi).sqrt())
            / self.truth
            - 1.0
    }
    /// Relative error of the band's minimax centre 2·lo·hi/(lo + hi): the prediction whose
    /// worst error over the figures the band spans is least (docs/validation.md, "What a
    /// page cannot tell"). The value itself where there is no band.
    fn minimax_error(&self) -> f64 {
        self.band
            .filter(|(lo, hi)| *lo > 0.0 && *hi > 0.0)
            .map_or(self.value, |(lo, hi)| 2.0 * lo * hi / (lo + hi))
            / self.truth
            - 1.0
    }
}

/// One motor's evaluation.
#[derive(Debug, Clone)]
struct Motor {
    seed: u64,
    v_disp_cm3: f64,
    displacement_printed: bool,
    supply: &'static str,
    /// `figures[p][k]`: pressure p of [`BAR_G`], figure k of [`FIGURES`].
    figures: Vec<[Check; 7]>,
    /// `factors[p][k]`: pressure p, factor k of [`FACTORS`].
    factors: Vec<[Check; 4]>,
    /// The fit said it did not reach the noise.
    noise_not_reached: bool,
    /// What `vanefit fit` printed.
    fit_stdout: String,
    /// The fit's displacement, m³, and its 95 % interval if it has one.
    v_disp_fit: (f64, Option<[f64; 2]>),
}

/// Why a motor was not evaluated.
#[derive(Debug, Clone)]
enum Failure {
    /// vanefit refused the page (exit status 1 of `fit`: a message naming the page's file,
    /// line and column).
    Refused(String),
    /// Anything else: the twin, a crash, `predict`, unreadable output.
    Failed(String),
}

impl From<String> for Failure {
    fn from(e: String) -> Self {
        Failure::Failed(e)
    }
}

/// Runs vanefit; Err((exit code, message)).
fn vanefit(args: &[&str]) -> Result<String, (Option<i32>, String)> {
    let out = Command::new(crate::every_size::vanefit_bin())
        .args(args)
        .output()
        .map_err(|e| (None, e.to_string()))?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).into_owned())
    } else {
        Err((
            out.status.code(),
            format!(
                "vanefit {} exited {}: {}",
                args[0],
                out.status,
                String::from_utf8_lossy(&out.stderr).trim()
            ),
        ))
    }
}

/// A CSV as its rows of (column → cell).
pub(crate) fn table(path: &Path) -> Result<Vec<std::collections::HashMap<String, String>>, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().ok_or("empty csv")?.split(',').collect();
    Ok(lines
        .map(|l| {
            header
                .iter()
                .zip(l.split(','))
                .map(|(h, v)| (h.to_string(), v.to_string()))
                .collect()
        })
        .collect())
}

/// (value, band) of `column` in a row: the band is `None` when its cells are empty.
pub(crate) fn banded(
    row: &std::collections::HashMap<String, String>,
    column: &str,
) -> Result<(f64, Option<(f64, f64)>), String> {
    let num = |c: &str| row.get(c).and_then(|v| v.parse::<f64>().ok());
    let value = num(column).ok_or(format!("no value in column {column}"))?;
    let band = num(&format!("{column}_lo")).zip(num(&format!("{column}_hi")));
    Ok((value, band))
}

/// Prints, fits and predicts the page of motor `seed` in `dir`; `starts` overrides the fit's
/// number of starts (`None`: vanefit's default).
fn evaluate(seed: u64, dir: &Path, starts: Option<usize>) -> Result<Motor, Failure> {
    evaluate_styled(seed, dir, starts, None, None)
}

/// [`evaluate`] with the page's displacement printed or not as `displacement` says (`None`:
/// as the page style drew it), and `predict_extra` added to predict's options (`None`: those
/// of PAGE_PREDICT_ARGS).
fn evaluate_styled(
    seed: u64,
    dir: &Path,
    starts: Option<usize>,
    displacement: Option<bool>,
    predict_extra: Option<&str>,
) -> Result<Motor, Failure> {
    let motor = random_motor(seed, &SPREAD);
    let mut style = page_style(seed);
    if let Some(d) = displacement {
        style.displacement = d;
    }
    let page_dir = dir.join("page");
    std::fs::create_dir_all(&page_dir).map_err(|e| e.to_string())?;
    let page = print_page(&page_dir, &motor, &style).map_err(|e| format!("twin: {e}"))?;
    let oracle = Oracle::from_env(&motor);
    oracle.tell_page(&page_dir)?;
    second_pressure(&page_dir, &motor)?;
    let (rows, factors) =
        truth(&motor, &BAR_G, REFERENCE_BAR_G).map_err(|e| format!("twin: {e}"))?;
    let fit = dir.join("fit.json");
    let (fit_s, page_s) = (fit.to_str().unwrap(), page_dir.to_str().unwrap());
    let starts_s = starts.map(|s| s.to_string());
    let mut args = vec![
        "fit",
        page_s,
        "--out",
        fit_s,
        "--no-plots",
        "--threads",
        "1",
    ];
    if let Some(s) = &starts_s {
        args.extend(["--starts", s]);
    }
    let oracle_args = oracle.fit_args(style.displacement);
    args.extend(oracle_args.iter().map(String::as_str));
    // PAGE_FIT_ARGS adds options to fit (e.g. "--priors none"); default none.
    let fit_extra = std::env::var("PAGE_FIT_ARGS").unwrap_or_default();
    args.extend(fit_extra.split_whitespace());
    let fit_out = vanefit(&args).map_err(|(code, e)| match code {
        Some(1) => Failure::Refused(e),
        _ => Failure::Failed(e),
    })?;
    let pred = dir.join("predict");
    // PAGE_PREDICT_ARGS adds options to predict (e.g. "--fixed-spread 1.5"); default none.
    let extra = predict_extra.map_or_else(
        || std::env::var("PAGE_PREDICT_ARGS").unwrap_or_default(),
        str::to_string,
    );
    let mut args = vec![
        "predict",
        fit_s,
        "--pressures",
        "3,4,5,6,7",
        "--unit",
        "bar_g",
        "--out",
        pred.to_str().unwrap(),
    ];
    // "{page}" in PAGE_PREDICT_ARGS stands for the page's folder (e.g. "--bands samples
    // --data {page}").
    let extra = extra.replace("{page}", page_s);
    // The delta method unless the extra options ask otherwise (sampling takes seconds).
    if !extra.contains("--bands") {
        args.extend(["--bands", "delta"]);
    }
    args.extend(extra.split_whitespace());
    vanefit(&args).map_err(|(_, e)| Failure::Failed(e))?;
    let (cat, fac) = (
        table(&pred.join("catalogue.csv"))?,
        table(&pred.join("factors.csv"))?,
    );
    if cat.len() != BAR_G.len() || fac.len() != BAR_G.len() {
        return Err(format!("{} catalogue rows, {} factor rows", cat.len(), fac.len()).into());
    }
    let mut figures = Vec::new();
    let mut factor_checks = Vec::new();
    for p in 0..BAR_G.len() {
        let t = row_values(&rows[p]);
        let mut f = [Check {
            value: 0.0,
            band: None,
            truth: 0.0,
        }; 7];
        for (k, (col, per_si)) in COLUMNS.iter().enumerate() {
            let (value, band) = banded(&cat[p], col)?;
            f[k] = Check {
                value,
                band,
                truth: t[k] * per_si,
            };
        }
        figures.push(f);
        let mut g = [Check {
            value: 0.0,
            band: None,
            truth: 0.0,
        }; 4];
        for (k, col) in FACTORS.iter().enumerate() {
            let (value, band) = banded(&fac[p], col)?;
            g[k] = Check {
                value,
                band,
                truth: factors[p][k],
            };
        }
        factor_checks.push(g);
    }
    let v_disp_fit = fit_displacement(&fit)?;
    Ok(Motor {
        seed,
        fit_stdout: fit_out.clone(),
        v_disp_fit,
        v_disp_cm3: page.motor.v_disp * 1e6,
        displacement_printed: style.displacement,
        supply: style.supply.0,
        figures,
        factors: factor_checks,
        noise_not_reached: fit_out.contains("NOT reach"),
    })
}

/// Oracle experiments (not what a user can do; to find where the errors come from):
/// PAGE_ORACLE lists what of the twin's truth the fit is given, comma-separated: `geom`
/// (vanes and expansion ratio in the page's `[motor]`, the polytropic index fixed by
/// bounds), `coulomb` (the Coulomb friction fixed by bounds), `visc` (the viscous friction likewise), `dead` (the dead volume in
/// `[motor]`, still estimated). Empty: the fit as a user runs it.
struct Oracle {
    motor: twin::motor::TwinMotor,
    geom: bool,
    coulomb: bool,
    dead: bool,
    visc: bool,
}

impl Oracle {
    fn from_env(motor: &twin::motor::TwinMotor) -> Self {
        let v = std::env::var("PAGE_ORACLE").unwrap_or_default();
        Oracle {
            motor: motor.clone(),
            geom: v.contains("geom"),
            coulomb: v.contains("coulomb"),
            dead: v.contains("dead"),
            visc: v.contains("visc"),
        }
    }

    fn any(&self) -> bool {
        self.geom || self.coulomb || self.dead || self.visc
    }

    /// Writes what the oracle gives into the page's `[motor]` table.
    fn tell_page(&self, page_dir: &Path) -> Result<(), String> {
        let mut add = String::new();
        if self.geom {
            add += &format!(
                "vanes = {}\nexpansion_ratio = {}\n",
                self.motor.z as u32, self.motor.eps
            );
        }
        if self.dead {
            add += &format!("dead_volume_m3 = {:e}\n", self.motor.v_dead);
        }
        if add.is_empty() {
            return Ok(());
        }
        let path = page_dir.join("rig.toml");
        let text = std::fs::read_to_string(&path).map_err(|e| e.to_string())?;
        let text = text.replacen("[motor]\n", &format!("[motor]\n{add}"), 1);
        std::fs::write(&path, text).map_err(|e| e.to_string())
    }

    /// The fit options that fix what the oracle gives.
    fn fit_args(&self, displacement_printed: bool) -> Vec<String> {
        if !self.any() {
            return Vec::new();
        }
        let mut est = "c_in1,c_out2,c_ext,c_1e,c_2e,c_12,t_coulomb,visc,v_dead,b_crit".to_string();
        if !displacement_printed {
            est += ",v_disp";
        }
        let mut bounds = Vec::new();
        if self.geom {
            est += ",n_poly";
            let n = self.motor.n_poly;
            bounds.push(format!("n_poly={}:{}", n - 1e-6, n + 1e-6));
        }
        if self.coulomb {
            let t = self.motor.t_coulomb;
            bounds.push(format!("t_coulomb={:e}:{:e}", t * 0.999, t * 1.001));
        }
        if self.visc {
            let v = self.motor.visc;
            bounds.push(format!("visc={:e}:{:e}", v * 0.999, v * 1.001));
        }
        let mut args = vec!["--estimate".to_string(), est];
        if !bounds.is_empty() {
            args.extend(["--bounds".to_string(), bounds.join(",")]);
        }
        args
    }
}

/// PAGE_EXTRA adds a second catalogue experiment to the page: figures of the twin's motor
/// at another supply pressure, "name,name@bar_g" (names as in [`FIGURES`], e.g.
/// "stall_torque@4" or "free_speed,max_power,speed_at_max_power@4"), each to 3 digits in
/// rpm, W, N·m or l/s ANR (what a user measures at a second pressure; docs/validation.md,
/// "What a page cannot tell"). Empty: the page as printed.
fn second_pressure(page_dir: &Path, motor: &twin::motor::TwinMotor) -> Result<(), String> {
    let spec = std::env::var("PAGE_EXTRA").unwrap_or_default();
    let Some((names, bar)) = spec.split_once('@') else {
        return Ok(());
    };
    let bar_g: f64 = bar
        .trim()
        .parse()
        .map_err(|_| format!("PAGE_EXTRA: {spec}"))?;
    let (rows, _) = truth(motor, &[bar_g], bar_g).map_err(|e| format!("twin: {e}"))?;
    let values = row_values(&rows[0]);
    // Each figure in the unit the twin's pages print it in most plainly.
    let (speed, power, torque) = (&SPEED_UNITS[0], &POWER_UNITS[0], &TORQUE_UNITS[0]);
    let air = &AIR_UNITS[1];
    let units = [speed, power, speed, torque, torque, air, air];
    let mut text = format!(
        "\n[[experiment]]\nkind = \"catalogue\"\np_supply = \"{bar_g} bar(g)\"\n\n[experiment.figures]\n"
    );
    for name in names.split(',').map(str::trim) {
        let k = FIGURES
            .iter()
            .position(|f| *f == name)
            .ok_or(format!("PAGE_EXTRA: no figure {name}"))?;
        text += &format!(
            "{name} = \"{} {}\"\n",
            twin::page::significant(values[k] * units[k].per_si, 3),
            units[k].printed
        );
    }
    let path = page_dir.join("rig.toml");
    let mut toml = std::fs::read_to_string(&path).map_err(|e| e.to_string())?;
    toml += &text;
    std::fs::write(&path, toml).map_err(|e| e.to_string())
}

/// The displacement of a fit file, m³, and its 95 % interval where it has one.
fn fit_displacement(fit: &Path) -> Result<(f64, Option<[f64; 2]>), String> {
    let text = std::fs::read_to_string(fit).map_err(|e| e.to_string())?;
    let json: serde_json::Value = serde_json::from_str(&text).map_err(|e| e.to_string())?;
    let p = &json["parameters"]["v_disp"];
    let value = p["value"]
        .as_f64()
        .or_else(|| p.as_f64())
        .ok_or("no v_disp in the fit file")?;
    let ci = p["ci95"]
        .as_array()
        .and_then(|c| Some([c.first()?.as_f64()?, c.get(1)?.as_f64()?]));
    Ok((value, ci))
}

/// Every motor of `seeds`, in parallel (each motor's work depends on its seed only, so the
/// results do not depend on the thread count).
fn run(seeds: Vec<u64>, starts: Option<usize>) -> Vec<(u64, Result<Motor, Failure>)> {
    // PAGE_DIR keeps the pages, fits and predictions there (else a temporary folder).
    let tmp = tempfile::tempdir().unwrap();
    let root = std::env::var_os("PAGE_DIR").map_or(tmp.path().to_path_buf(), Into::into);
    seeds
        .into_par_iter()
        .map(|seed| {
            let dir = root.join(format!("m{seed}"));
            (seed, evaluate(seed, &dir, starts))
        })
        .collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

/// Summary of a set of checks.
#[derive(Debug, Clone, Copy)]
struct Stats {
    held: usize,
    total: usize,
    no_band: usize,
    median_half_width: f64,
    median_abs_error: f64,
    /// The error of largest magnitude, signed.
    worst_error: f64,
    /// The same for the bands' geometric centres ([`Check::centre_error`]).
    worst_centre_error: f64,
    /// Checks whose point prediction is more than 10 % off.
    over_10: usize,
    /// Worst error, median |error| and count over 10 % of the bands' minimax centres
    /// ([`Check::minimax_error`]).
    minimax: (f64, f64, usize),
}

fn stats<'a>(checks: impl Iterator<Item = &'a Check>) -> Stats {
    let c: Vec<&Check> = checks.collect();
    let signed_worst = |e: &dyn Fn(&Check) -> f64| {
        c.iter().map(|x| e(x)).fold(0.0f64, |a, e| {
            if e.abs() > a.abs() || e.is_nan() {
                e
            } else {
                a
            }
        })
    };
    let worst = signed_worst(&Check::error);
    let worst_centre = signed_worst(&Check::centre_error);
    let minimax = (
        signed_worst(&Check::minimax_error),
        median(c.iter().map(|x| x.minimax_error().abs()).collect()),
        c.iter().filter(|x| x.minimax_error().abs() > 0.1).count(),
    );
    Stats {
        over_10: c.iter().filter(|x| x.error().abs() > 0.1).count(),
        minimax,
        held: c.iter().filter(|x| x.holds()).count(),
        total: c.len(),
        no_band: c.iter().filter(|x| x.band.is_none()).count(),
        median_half_width: median(c.iter().map(|x| x.half_width()).collect()),
        median_abs_error: median(c.iter().map(|x| x.error().abs()).collect()),
        worst_error: worst,
        worst_centre_error: worst_centre,
    }
}

fn line(name: &str, s: &Stats) -> String {
    format!(
        "| {name} | {}/{} ({:.0} %) | {:.1} % | {:.1} % | {:+.1} % | {} | {:+.1} % | {} | {:+.1} % | {:.1} % | {} |",
        s.held,
        s.total,
        100.0 * s.held as f64 / s.total.max(1) as f64,
        100.0 * s.median_half_width,
        100.0 * s.median_abs_error,
        100.0 * s.worst_error,
        s.no_band,
        100.0 * s.worst_centre_error,
        s.over_10,
        100.0 * s.minimax.0,
        100.0 * s.minimax.1,
        s.minimax.2
    )
}

const HEAD: &str = "| | bands holding the truth | median half-width | median |error| | worst error | no band | worst error of √(lo·hi) | > 10 % off | worst error of 2·lo·hi/(lo+hi) | its median |error| | its > 10 % |\n|---|---|---|---|---|---|---|---|---|---|---|";

/// The markdown tables of the figures and factors of `motors`.
fn report(motors: &[&Motor]) -> String {
    let figs = || motors.iter().flat_map(|m| m.figures.iter().flatten());
    let facs = || motors.iter().flat_map(|m| m.factors.iter().flatten());
    let mut out = format!(
        "{HEAD}\n{}\n{}\n",
        line("all figures", &stats(figs())),
        line("all correction factors", &stats(facs()))
    );
    out += &format!("\nper figure (all pressures)\n\n{HEAD}\n");
    for (k, name) in FIGURES.iter().enumerate() {
        let s = stats(
            motors
                .iter()
                .flat_map(|m| m.figures.iter().map(move |f| &f[k])),
        );
        out += &(line(name, &s) + "\n");
    }
    for (k, name) in FACTORS.iter().enumerate() {
        let s = stats(
            motors
                .iter()
                .flat_map(|m| m.factors.iter().map(move |f| &f[k])),
        );
        out += &(line(&format!("factor {name}"), &s) + "\n");
    }
    out += &format!("\nper pressure (figures; factors)\n\n{HEAD}\n");
    for (p, bar) in BAR_G.iter().enumerate() {
        let s = stats(motors.iter().flat_map(|m| m.figures[p].iter()));
        out += &(line(&format!("figures at {bar} bar g"), &s) + "\n");
        let s = stats(motors.iter().flat_map(|m| m.factors[p].iter()));
        out += &(line(&format!("factors at {bar} bar g"), &s) + "\n");
    }
    out
}

/// What a study gives: the motors evaluated, the pages vanefit refused, the other failures.
struct Study {
    ok: Vec<Motor>,
    refused: Vec<(u64, String)>,
    failed: Vec<(u64, String)>,
}

/// Runs `n` motors and prints the tables.
fn study(seeds: Vec<u64>, starts: Option<usize>) -> Study {
    let t0 = std::time::Instant::now();
    let n = seeds.len();
    let results = run(seeds, starts);
    let mut s = Study {
        ok: Vec::new(),
        refused: Vec::new(),
        failed: Vec::new(),
    };
    for (seed, r) in results {
        match r {
            Ok(m) => s.ok.push(m),
            Err(Failure::Refused(e)) => s.refused.push((seed, e)),
            Err(Failure::Failed(e)) => s.failed.push((seed, e)),
        }
    }
    println!(
        "{n} motors: {} evaluated, {} pages refused by vanefit, {} failed; fit starts {}; {:.0} s wall\n",
        s.ok.len(),
        s.refused.len(),
        s.failed.len(),
        starts.map_or("default".to_string(), |s| s.to_string()),
        t0.elapsed().as_secs_f64()
    );
    for (seed, e) in &s.refused {
        println!("motor {seed} refused: {e}");
    }
    for (seed, e) in &s.failed {
        println!("motor {seed} failed: {e}");
    }
    let ok = &s.ok;
    let all: Vec<&Motor> = ok.iter().collect();
    println!("\n## all pages\n\n{}", report(&all));
    let with: Vec<&Motor> = ok.iter().filter(|m| m.displacement_printed).collect();
    let without: Vec<&Motor> = ok.iter().filter(|m| !m.displacement_printed).collect();
    println!(
        "## pages that print the displacement ({})\n\n{}",
        with.len(),
        report(&with)
    );
    if !without.is_empty() {
        println!(
            "## pages without a displacement ({})\n\n{}",
            without.len(),
            report(&without)
        );
    }
    println!("per motor: seed, V_disp cm³, displacement printed, supply, figures held/35, factors held/20, worst figure error, noise not reached; the twin's free speed rpm, max power W, stall torque N·m at 6 bar g");
    for m in ok {
        let f = stats(m.figures.iter().flatten());
        let g = stats(m.factors.iter().flatten());
        println!(
            "{} {:.2} {} {:?} {}/35 {}/20 {:+.1} % {}; {:.0} {:.1} {:.3}",
            m.seed,
            m.v_disp_cm3,
            m.displacement_printed,
            m.supply,
            f.held,
            g.held,
            100.0 * f.worst_error,
            m.noise_not_reached,
            m.figures[3][0].truth,
            m.figures[3][1].truth,
            m.figures[3][4].truth,
        );
        // PAGE_SHOW_MOTOR=1 prints the twin's motor (its true parameters) too.
        if std::env::var_os("PAGE_SHOW_MOTOR").is_some() {
            println!("  {:?}", random_motor(m.seed, &SPREAD));
        }
    }
    s
}

/// Number from the environment, else `default`.
fn env_or<T: std::str::FromStr>(name: &str, default: T) -> T {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

#[test]
#[ignore = "long: ≥ 50 motors through fit and predict; run with --ignored --nocapture"]
fn page_coverage_table_over_random_motors() {
    // PAGE_MOTORS (default 60, so that ≥ 50 remain after the pages vanefit refuses) and
    // PAGE_STARTS (default: vanefit fit's own) size the run.
    let n = env_or("PAGE_MOTORS", 60u64);
    let starts = std::env::var("PAGE_STARTS")
        .ok()
        .and_then(|v| v.parse().ok());
    // PAGE_PREDICT_ARGS adds predict options. PAGE_SEEDS (comma-separated) picks motors instead, e.g. to look at pages again with
    // PAGE_DIR.
    let seeds = std::env::var("PAGE_SEEDS").map_or((0..n).collect(), |v| {
        v.split(',').map(|s| s.trim().parse().unwrap()).collect()
    });
    let s = study(seeds, starts);
    assert!(s.failed.is_empty(), "{:?}", s.failed);
}

#[test]
fn pages_of_random_motors_fit_and_predict_end_to_end() {
    // Six motors (seeds 0–5: 1.5–15 cm³, mixed units, one supply each), 8 starts.
    let s = study((0..6).collect(), Some(8));
    // Every page the twin prints is in the documented format and true to one motor: vanefit
    // reads, fits and predicts it, or refuses it with a message at the page's file, line and
    // column (today: a power above torque·speed from linear interpolation on sparse torque
    // points, where the true torque curve bows above the chord). Never a crash.
    assert!(s.failed.is_empty(), "{:?}", s.failed);
    for (_, e) in &s.refused {
        assert!(e.contains("rig.toml:") || e.contains(".csv:"), "{e}");
    }
    assert!(s.ok.len() >= 4, "{} of 6 evaluated", s.ok.len());
    for m in &s.ok {
        for c in m.figures.iter().flatten().chain(m.factors.iter().flatten()) {
            assert!(
                c.value.is_finite() && c.value > 0.0,
                "motor {}: {c:?}",
                m.seed
            );
            assert!(
                c.truth.is_finite() && c.truth > 0.0,
                "motor {}: {c:?}",
                m.seed
            );
        }
    }
    // A motor's results depend on its seed only: motor 0 alone gives what it gave among six
    // running in parallel.
    let again = study(vec![0], Some(8));
    if let (Some(a), Some(b)) = (s.ok.iter().find(|m| m.seed == 0), again.ok.first()) {
        let bits = |m: &Motor| -> Vec<u64> {
            m.figures
                .iter()
                .flatten()
                .chain(m.factors.iter().flatten())
                .flat_map(|c| {
                    let (lo, hi) = c.band.unwrap_or((f64::NAN, f64::NAN));
                    [c.value, lo, hi].map(f64::to_bits)
                })
                .collect()
        };
        assert_eq!(bits(a), bits(b));
    }
    // Bounds from what these six motors give with the page fixes (60-motor table: figure
    // bands 99 %, factor bands 97 %, median half-width 8.5 %; these six: every band holds,
    // worst errors 2–10 %), with a margin for the 8 starts: every figure at 3–7 bar g within
    // 15 %, at least 90 % of the figure and of the factor bands hold the truth, the median
    // figure band is at most ±12 % wide. (Before: worst error 19 % and bands of 83–95 %.)
    for m in &s.ok {
        let e = stats(m.figures.iter().flatten()).worst_error;
        assert!(e.abs() < 0.15, "motor {}: worst error {e}", m.seed);
    }
    let figs = stats(s.ok.iter().flat_map(|m| m.figures.iter().flatten()));
    let facs = stats(s.ok.iter().flat_map(|m| m.factors.iter().flatten()));
    for (what, st) in [("figure", figs), ("factor", facs)] {
        assert!(
            st.held * 10 >= st.total * 9,
            "{what} bands: {}/{} hold the truth",
            st.held,
            st.total
        );
    }
    assert!(figs.median_half_width <= 0.12, "{figs:?}");
}

/// Bands from posterior samples on the three pages of the 60-motor table where they held the
/// truth least (motors 10, 32 and 59: 22, 25 and 28 of 35 figure bands with the stretch move
/// alone, which left R̂ at 1.3–2.0 after 4000 steps; the delta method held 35 of 35 on each).
/// The pages print one pressure and cannot split the friction into its Coulomb and viscous
/// parts; a sampler that explores the posterior carries that into the bands at 3–5 bar g.
#[test]
fn sampled_bands_hold_the_truth_on_pages_a_slow_sampler_missed() {
    let tmp = tempfile::tempdir().unwrap();
    let results: Vec<(u64, Result<Motor, Failure>)> = [10u64, 32, 59]
        .into_par_iter()
        .map(|seed| {
            let dir = tmp.path().join(format!("m{seed}"));
            let extra = "--bands samples --data {page}";
            (seed, evaluate_styled(seed, &dir, None, None, Some(extra)))
        })
        .collect();
    let mut ok = Vec::new();
    for (seed, r) in results {
        match r {
            Ok(m) => ok.push(m),
            Err(Failure::Refused(e) | Failure::Failed(e)) => panic!("motor {seed}: {e}"),
        }
    }
    let figs = stats(ok.iter().flat_map(|m| m.figures.iter().flatten()));
    let facs = stats(ok.iter().flat_map(|m| m.factors.iter().flatten()));
    println!("figures {figs:?}\nfactors {facs:?}");
    // Every figure has a band, and as many hold the truth as a 95 % band should over these
    // 105 figures (at least 90 %; before: 75 of 105).
    assert_eq!(figs.no_band, 0, "{figs:?}");
    assert!(figs.held * 10 >= figs.total * 9, "figure bands: {figs:?}");
}

#[test]
fn pages_without_their_displacement_are_sized_from_the_page() {
    // Motors 0–3 (3.6 to 8.9 cm³), their pages printed without the displacement: `fit`
    // estimates it from the page with the other parameters and says so, and the estimate
    // and the predictions hold as on the page that prints it (before, such a page was fitted
    // as the 3.8 cm³ reference motor: figures off by up to a factor of 7 over the 60-motor
    // table).
    let tmp = tempfile::tempdir().unwrap();
    let results: Vec<(u64, Result<Motor, Failure>)> = (0..4u64)
        .into_par_iter()
        .map(|seed| {
            let dir = tmp.path().join(format!("m{seed}"));
            (
                seed,
                evaluate_styled(seed, &dir, Some(8), Some(false), None),
            )
        })
        .collect();
    let mut held = 0;
    for (seed, r) in results {
        let m = r.unwrap_or_else(|e| panic!("motor {seed}: {e:?}"));
        // One displacement estimate per page: the fit's own, not the similarity estimate's
        // beside it.
        assert_eq!(
            m.fit_stdout
                .matches("displacement estimated from the page:")
                .count(),
            1,
            "motor {seed}: {}",
            m.fit_stdout
        );
        let truth = m.v_disp_cm3 * 1e-6;
        let (v, ci) = m.v_disp_fit;
        assert!(
            (v / truth - 1.0).abs() < 0.15,
            "motor {seed}: displacement {v:e} m³, truth {truth:e}"
        );
        held += usize::from(ci.is_some_and(|[lo, hi]| lo <= truth && truth <= hi));
        let worst = stats(m.figures.iter().flatten()).worst_error;
        println!("motor {seed}: displacement {v:e} m³ {ci:?}, truth {truth:e}; worst figure error {worst:+.3}");
        assert!(
            worst.abs() < 0.3,
            "motor {seed}: worst figure error {worst}"
        );
    }
    // Nominal 95 %: 4 of 4 expected; 3 allows one miss.
    assert!(
        held >= 3,
        "{held} of 4 displacement intervals hold the truth"
    );
    // `check` says what the fit will start from.
    let page = tmp.path().join("m0").join("page");
    let out = vanefit(&["check", page.to_str().unwrap()]).unwrap();
    assert!(
        out.contains("displacement estimated from the page:") && out.contains("cm³ ["),
        "{out}"
    );
}

#[test]
fn page_units_read_back_as_the_twin_printed_them() {
    // The twin converts to the page's units with its own constants; `vanefit check` reads
    // them back to SI with vanefit's. Each key figure must come back as the twin's SI value
    // within the 3-digit rounding (≤ 0.5 % relative), for pages of every unit drawn.
    let names = [
        ("free speed", 0),
        ("max power", 1),
        ("speed at max power", 2),
        ("torque at max power", 3),
        ("stall torque", 4),
        ("air consumption at max power", 5),
        ("air consumption at free speed", 6),
    ];
    let dir = tempfile::tempdir().unwrap();
    let mut units_seen = std::collections::BTreeSet::new();
    let mut compared = 0;
    for seed in 0..24u64 {
        let page_dir = dir.path().join(format!("p{seed}"));
        std::fs::create_dir_all(&page_dir).unwrap();
        let style = page_style(seed);
        let page = print_page(&page_dir, &random_motor(seed, &SPREAD), &style).unwrap();
        units_seen.extend(style.units.map(|u| u.printed));
        let out = match vanefit(&["check", page_dir.to_str().unwrap()]) {
            Ok(out) => out,
            // A page refused at its file, line and column (see the end-to-end test).
            Err((Some(1), e)) if e.contains(".csv:") || e.contains("rig.toml:") => continue,
            Err(e) => panic!("{e:?}"),
        };
        let truth = row_values(&page.row);
        for line in out.lines().map(str::trim) {
            // "free speed   10200 rpm   =   1068.1415 rad_s"
            let Some((left, right)) = line.split_once(" = ") else {
                continue;
            };
            let Some((name, k)) = names.iter().find(|(n, _)| {
                left.starts_with(n) && left[n.len()..].starts_with(char::is_whitespace)
            }) else {
                continue;
            };
            let si: f64 = right.split_whitespace().next().unwrap().parse().unwrap();
            let rel = si / truth[*k] - 1.0;
            assert!(
                rel.abs() <= 0.0051,
                "seed {seed}, {name}: vanefit reads {si} SI, twin {}",
                truth[*k]
            );
            compared += 1;
        }
    }
    println!("{compared} figures compared, units {units_seen:?}");
    assert!(compared >= 24 * 3, "{compared}");
    assert!(units_seen.len() >= 12, "{units_seen:?}");
}
