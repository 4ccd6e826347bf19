//! Rig recordings of motors of every size (0.5–250 cm³), written by the independent twin
//! with the rig scaled to the motor (tests/twin/sizes.rs: brake, throttle range, sensor
//! noise and offsets), each fitted by `vanefit fit` as a user runs it (few starts), the fit
//! file's estimates and 95 % intervals judged against the twin's truth (docs/validation.md,
//! "Every size and page style").
//!
//! Per size band: how many intervals hold the truth, the worst estimate error, the
//! estimates on a bound of the search (within 1e-3 relative of it: the fit file's bounds
//! where it records them, else the search bounds vanefit prints in `export-petab`'s
//! parameters.tsv), the noise ratio, and the fit's time against the same datasets at
//! 3.8 cm³ (the reference motor; seeds 1.. are tests/estimate/coverage.rs's cases).
//!
//! ```sh
//! RIG_PER_BAND=3 RIG_STARTS=4 VANEFIT_BIN=/tmp/vanefit-a7f cargo test --release \
//!     --test estimate -- --ignored --nocapture every_size_rig_table
//! ```
//!
//! Knobs: `RIG_PER_BAND` (datasets per band, default 3), `RIG_STARTS` (`fit --starts`,
//! default 4), `RIG_BANDS` (indices of [`SIZE_BANDS_CM3`], default all), `RIG_THREADS`
//! (fits at once, default 2), `RIG_OUT` (default target/every-size-rigs.md), `RIG_DIR` (keep
//! the datasets and fits there), `VANEFIT_BIN`. Under the tables, each parameter's errors in
//! its fits' own σ (`z_table`): whether an estimate beyond 10 % is the noise's or a bias.

use crate::twin;

use rayon::prelude::*;
use std::path::Path;
use std::process::Command;
use twin::files::parameters;
use twin::sizes::{
    band_label, displacement_in_band, perturbed_motor_sized, scaled_rig_config, RIG_RANGE_CM3,
    SIZE_BANDS_CM3,
};

/// The normal quantile of a two-sided 95 % interval.
const Z95: f64 = 1.959_963_984_540_054;

/// Standard normal Φ(z) by the complementary error function (Numerical Recipes' `erfcc`,
/// relative error < 1.2e-7).
fn normal_cdf(z: f64) -> f64 {
    let x = -z / std::f64::consts::SQRT_2;
    let a = x.abs();
    let t = 1.0 / (1.0 + 0.5 * a);
    let poly = [
        -1.265_512_23,
        1.000_023_68,
        0.374_091_96,
        0.096_784_18,
        -0.186_288_06,
        0.278_868_07,
        -1.135_203_98,
        1.488_515_87,
        -0.822_152_23,
        0.170_872_77,
    ];
    let horner = poly.iter().rev().fold(0.0, |acc, c| c + t * acc);
    let r = t * (-a * a + horner).exp();
    0.5 * if x >= 0.0 { r } else { 2.0 - r }
}

fn vanefit_bin() -> String {
    std::env::var("VANEFIT_BIN").unwrap_or_else(|_| env!("CARGO_BIN_EXE_vanefit").to_string())
}

/// One estimated parameter against the truth.
#[derive(Debug, Clone)]
struct Estimate {
    name: String,
    truth: f64,
    value: f64,
    /// The interval's ends (`None`: open on that side or no interval).
    lo: Option<f64>,
    hi: Option<f64>,
    /// The search bounds.
    bounds: Option<(f64, f64)>,
    /// The fit file gives a closed 95 % interval (`ci95`), not only the ends that closed.
    closed: bool,
}

impl Estimate {
    fn covers(&self) -> bool {
        self.lo.is_none_or(|lo| lo <= self.truth) && self.hi.is_none_or(|hi| self.truth <= hi)
    }
    fn error(&self) -> f64 {
        self.value / self.truth - 1.0
    }
    /// σ of ln v from the 95 % interval's end on the truth's side, ln(end/v)/1.96 (`None`
    /// where that end is open).
    fn sd_ln(&self) -> Option<f64> {
        let end = if self.truth >= self.value {
            self.hi
        } else {
            self.lo
        }?;
        (end > 0.0 && self.value > 0.0).then(|| (end / self.value).ln().abs() / Z95)
    }
    /// z = ln(v/truth)/σ: the error in the fit's own standard deviations.
    fn z(&self) -> Option<f64> {
        self.sd_ln().map(|sd| (self.value / self.truth).ln() / sd)
    }
    /// The probability that an estimate with this interval's σ (ln-normal around the truth)
    /// errs by more than 10 % either way: Φ(ln 0.9/σ) + Φ(−ln 1.1/σ).
    fn p_beyond_10pct(&self) -> Option<f64> {
        self.sd_ln()
            .map(|sd| normal_cdf(0.9f64.ln() / sd) + normal_cdf(-(1.1f64.ln()) / sd))
    }
    /// Within 1e-3 relative of a search bound.
    fn on_bound(&self) -> bool {
        let near = |b: f64| (self.value - b).abs() <= 1e-3 * b.abs();
        self.bounds.is_some_and(|(lo, hi)| near(lo) || near(hi))
    }
}

/// One dataset's fit.
#[derive(Debug, Clone)]
struct Fitted {
    v_cm3: f64,
    seed: u64,
    estimates: Vec<Estimate>,
    noise_ratio: f64,
    wall_s: f64,
}

/// Writes the twin dataset of `seed` at `v_disp_m3` into `dir` and fits it.
fn fit_case(seed: u64, v_disp_m3: f64, starts: &str, dir: &Path) -> Result<Fitted, String> {
    let motor = perturbed_motor_sized(seed, v_disp_m3);
    let data = dir.join("data");
    twin::write_dataset(&data, &motor, &scaled_rig_config(seed, v_disp_m3), seed)
        .map_err(|e| format!("twin: {e}"))?;
    let fit = dir.join("fit.json");
    let (data_s, fit_s) = (data.to_str().unwrap(), fit.to_str().unwrap());
    let args = [
        "fit",
        data_s,
        "--out",
        fit_s,
        "--no-plots",
        "--threads",
        "1",
        "--starts",
        starts,
    ];
    let stdout = run(&args)?;
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&fit).map_err(|e| e.to_string())?)
            .map_err(|e| e.to_string())?;
    let petab = search_bounds(&json, &fit, &data, dir);
    let truth = parameters(&motor);
    let mut estimates = Vec::new();
    for (name, p) in json["parameters"].as_object().ok_or("no parameters")? {
        if p["estimated"] != serde_json::Value::Bool(true) {
            continue;
        }
        let Some(&(_, t, _)) = truth.iter().find(|(n, _, _)| n == name) else {
            continue;
        };
        let ends = |k: &str| -> (Option<f64>, Option<f64>) {
            let a = p[k].as_array();
            (
                a.and_then(|a| a.first()?.as_f64()),
                a.and_then(|a| a.get(1)?.as_f64()),
            )
        };
        let (lo, hi) = if p["ci95"].is_array() {
            ends("ci95")
        } else {
            ends("bounds95")
        };
        let recorded = recorded_bounds(p);
        estimates.push(Estimate {
            name: name.clone(),
            truth: t,
            value: p["value"].as_f64().ok_or("no value")?,
            lo,
            hi,
            closed: p["ci95"].is_array(),
            bounds: recorded.or_else(|| petab.iter().find(|(n, _)| n == name).map(|(_, b)| *b)),
        });
    }
    Ok(Fitted {
        v_cm3: v_disp_m3 * 1e6,
        seed,
        estimates,
        noise_ratio: json["statistics"]["noise_ratio"]
            .as_f64()
            .unwrap_or(f64::NAN),
        wall_s: crate::common::fit_wall_s(&fit, &stdout).unwrap_or(f64::NAN),
    })
}

/// The search bounds a fit file records for a parameter, `[lo, hi]` under `bounds` or
/// `search_bounds` (SI), if it does.
fn recorded_bounds(p: &serde_json::Value) -> Option<(f64, f64)> {
    let b = p["bounds"]
        .as_array()
        .or_else(|| p["search_bounds"].as_array())?;
    Some((b.first()?.as_f64()?, b.get(1)?.as_f64()?))
}

/// The search bounds vanefit prints for the fit (`export-petab`'s parameters.tsv:
/// lowerBound, upperBound per parameterId), unless every estimate in the fit file records
/// its own.
fn search_bounds(
    json: &serde_json::Value,
    fit: &Path,
    data: &Path,
    dir: &Path,
) -> Vec<(String, (f64, f64))> {
    let recorded = json["parameters"].as_object().is_some_and(|ps| {
        ps.values()
            .filter(|p| p["estimated"] == serde_json::Value::Bool(true))
            .all(|p| recorded_bounds(p).is_some())
    });
    if recorded {
        return Vec::new();
    }
    let out = dir.join("petab");
    let args = [
        "export-petab",
        "--dataset",
        data.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        fit.to_str().unwrap(),
    ];
    if run(&args).is_err() {
        return Vec::new();
    }
    let text = std::fs::read_to_string(out.join("parameters.tsv")).unwrap_or_default();
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let c: Vec<&str> = l.split('\t').collect();
            Some((
                c.first()?.to_string(),
                (c.get(3)?.parse().ok()?, c.get(4)?.parse().ok()?),
            ))
        })
        .collect()
}

fn run(args: &[&str]) -> Result<String, String> {
    let out = Command::new(vanefit_bin())
        .args(args)
        .output()
        .map_err(|e| e.to_string())?;
    if out.status.success() {
        Ok(String::from_utf8_lossy(&out.stdout).into_owned())
    } else {
        let err = String::from_utf8_lossy(&out.stderr);
        Err(format!(
            "vanefit {} {}: {}",
            args[0],
            out.status,
            err.lines().next().unwrap_or("")
        ))
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(f64::NAN)
}

/// One band's row: datasets, intervals holding the truth, worst error, on a bound, noise
/// ratios, fit time and its ratio to the reference's.
fn band_line(label: &str, fits: &[Fitted], failed: usize, reference_s: f64) -> String {
    let all: Vec<&Estimate> = fits.iter().flat_map(|f| &f.estimates).collect();
    let pct = |k: usize| {
        format!(
            "{k}/{} ({:.0} %)",
            all.len(),
            100.0 * k as f64 / all.len().max(1) as f64
        )
    };
    let closed_held = all.iter().filter(|e| e.closed && e.covers()).count();
    let held = all.iter().filter(|e| e.covers()).count();
    let worst = fits
        .iter()
        .flat_map(|f| f.estimates.iter().map(move |e| (e, f.v_cm3)))
        .max_by(|a, b| a.0.error().abs().total_cmp(&b.0.error().abs()))
        .map_or("–".into(), |(e, v)| {
            format!("{:+.1} % ({}, {v:.2} cm³)", 100.0 * e.error(), e.name)
        });
    let mut bound: std::collections::BTreeMap<&str, usize> = Default::default();
    for e in all.iter().filter(|e| e.on_bound()) {
        *bound.entry(e.name.as_str()).or_default() += 1;
    }
    let n_bound: usize = bound.values().sum();
    let which: Vec<String> = bound.iter().map(|(n, k)| format!("{n} ×{k}")).collect();
    let with_bounds = all.iter().filter(|e| e.bounds.is_some()).count();
    let ratios: Vec<f64> = fits.iter().map(|f| f.noise_ratio).collect();
    let max_ratio = ratios.iter().copied().fold(f64::NAN, f64::max);
    let wall = median(fits.iter().map(|f| f.wall_s).collect());
    format!(
        "| {label} | {} | {failed} | {} | {} | {} | {worst} | {n_bound} of {with_bounds}{} | {:.2} / {max_ratio:.2} | {wall:.1} | {:.2} |",
        fits.len(),
        pct(closed_held),
        pct(held),
        all.iter().filter(|e| !e.closed).count(),
        if which.is_empty() { String::new() } else { format!(" ({})", which.join(", ")) },
        median(ratios),
        wall / reference_s,
    )
}

const HEAD: &str = "| size band | datasets fitted | failed | closed 95 % intervals holding the truth | intervals holding it, an open end unbounded | estimates without a closed interval | worst estimate error | estimates on a bound | noise ratio median / max | median fit s | fit time / 3.8 cm³'s |\n|---|---|---|---|---|---|---|---|---|---|---|";

/// Per parameter over all fits: the errors in the fits' own σ (z = ln(v/truth)/σ, σ from
/// the interval's end on the truth's side), how many lie beyond ±1.96, and how many
/// estimates the fits' own σ expect to err by more than 10 % (Σ P(|error| > 10 %)): where
/// that is near or above 1, an estimate beyond 10 % is the noise's, not a bias.
fn z_table(fits: &[&Fitted]) -> String {
    let mut by: std::collections::BTreeMap<&str, Vec<&Estimate>> = Default::default();
    for e in fits.iter().flat_map(|f| &f.estimates) {
        by.entry(e.name.as_str()).or_default().push(e);
    }
    let mut s = String::from("\n| parameter | estimates with a σ | mean z | sd of z | \\|z\\| > 1.96 | largest \\|z\\| | median σ of ln v | largest σ of ln v | expected > 10 % off (Σ P) | > 10 % off |\n|---|---|---|---|---|---|---|---|---|---|\n");
    let mut total = (0.0, 0usize);
    for (name, es) in &by {
        let z: Vec<f64> = es.iter().filter_map(|e| e.z()).collect();
        let sd: Vec<f64> = es.iter().filter_map(|e| e.sd_ln()).collect();
        let n = z.len() as f64;
        let mean = z.iter().sum::<f64>() / n;
        let var = z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
        let expected: f64 = es.iter().filter_map(|e| e.p_beyond_10pct()).sum();
        let off = es.iter().filter(|e| e.error().abs() > 0.1).count();
        total = (total.0 + expected, total.1 + off);
        s += &format!(
            "| {name} | {} | {mean:+.2} | {:.2} | {} | {:.2} | {:.2} % | {:.2} % | {expected:.2} | {off} |\n",
            z.len(),
            var.sqrt(),
            z.iter().filter(|v| v.abs() > Z95).count(),
            z.iter().fold(0.0f64, |a, v| a.max(v.abs())),
            100.0 * median(sd.clone()),
            100.0 * sd.iter().copied().fold(0.0, f64::max),
        );
    }
    s + &format!("| all | | | | | | | | {:.2} | {} |\n", total.0, total.1)
}

/// A size band of [`SIZE_BANDS_CM3`] cut to the rigs' range [`RIG_RANGE_CM3`], cm³.
fn rig_band(b: usize) -> (f64, f64) {
    (
        SIZE_BANDS_CM3[b].0.max(RIG_RANGE_CM3.0),
        SIZE_BANDS_CM3[b].1.min(RIG_RANGE_CM3.1),
    )
}

/// A fit's row of the per-dataset table.
fn dataset_line(band: &str, f: &Fitted) -> String {
    let names = |keep: &dyn Fn(&Estimate) -> bool| -> String {
        let v: Vec<&str> = f
            .estimates
            .iter()
            .filter(|e| keep(e))
            .map(|e| e.name.as_str())
            .collect();
        v.join(", ")
    };
    let worst = f
        .estimates
        .iter()
        .max_by(|a, b| a.error().abs().total_cmp(&b.error().abs()))
        .map_or("–".into(), |e| {
            let z = e.z().map_or(String::new(), |z| format!(" (z {z:+.2})"));
            format!("{} {:+.1} %{z}", e.name, 100.0 * e.error())
        });
    format!(
        "| {band} | {} | {:.2} | {:.2} | {} | {worst} | {} | {:.1} |",
        f.seed,
        f.v_cm3,
        f.noise_ratio,
        names(&|e| !e.covers()),
        names(&|e| e.on_bound()),
        f.wall_s
    )
}

/// Each job (band, seed, displacement m³) written and fitted, `threads` at a time.
fn run_jobs(
    jobs: &[(Option<usize>, u64, f64)],
    starts: &str,
    threads: usize,
) -> Vec<(Option<usize>, Result<Fitted, String>)> {
    // RIG_DIR keeps the datasets and fits there (else a temporary folder).
    let tmp = tempfile::tempdir().unwrap();
    let root = std::env::var_os("RIG_DIR").map_or(tmp.path().to_path_buf(), Into::into);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        jobs.par_iter()
            .map(|&(b, seed, v)| {
                let dir = root.join(format!("{b:?}-{seed}"));
                let r = fit_case(seed, v, starts, &dir);
                let brief = r.as_ref().map(|f| (f.noise_ratio, f.wall_s));
                eprintln!("band {b:?} seed {seed} {:.2} cm³: {brief:?}", v * 1e6);
                (b, r)
            })
            .collect()
    })
}

#[test]
#[ignore = "long: rig datasets of every size written and fitted; run with --ignored --nocapture"]
fn every_size_rig_table() {
    let env = |k: &str| std::env::var(k).ok();
    let n: u64 = env("RIG_PER_BAND")
        .and_then(|v| v.parse().ok())
        .unwrap_or(3);
    let starts = env("RIG_STARTS").unwrap_or("4".into());
    let threads: usize = env("RIG_THREADS").and_then(|v| v.parse().ok()).unwrap_or(2);
    let bands: Vec<usize> = env("RIG_BANDS").map_or((0..SIZE_BANDS_CM3.len()).collect(), |v| {
        v.split(',').filter_map(|x| x.trim().parse().ok()).collect()
    });
    // Band None: the reference motor (3.8 cm³), the same seeds.
    let mut jobs: Vec<(Option<usize>, u64, f64)> = (1..=n).map(|s| (None, s, 3.8e-6)).collect();
    for &b in &bands {
        jobs.extend((1..=n).map(|s| (Some(b), s, displacement_in_band(s, rig_band(b)))));
    }
    let t0 = std::time::Instant::now();
    let results = run_jobs(&jobs, &starts, threads);
    let of = |band: Option<usize>| -> (Vec<Fitted>, Vec<String>) {
        let mine = results.iter().filter(|(b, _)| *b == band).map(|(_, r)| r);
        let ok = mine
            .clone()
            .filter_map(|r| r.as_ref().ok().cloned())
            .collect();
        (ok, mine.filter_map(|r| r.as_ref().err().cloned()).collect())
    };
    let (reference, mut failures) = of(None);
    let reference_s = median(reference.iter().map(|f| f.wall_s).collect());
    let mut md = format!(
        "Binary: `{}`; {n} dataset(s) per size band (seeds 1..={n}: tests/estimate/coverage.rs's motors and recording configurations, scaled), `fit --starts {starts} --threads 1`; {:.0} s wall on {threads} threads.\n\n{HEAD}\n",
        vanefit_bin(),
        t0.elapsed().as_secs_f64()
    );
    md += &band_line(
        "3.8 cm³ (reference)",
        &reference,
        failures.len(),
        reference_s,
    );
    let mut per_dataset = String::from("\n\n| size band | seed | V_disp cm³ | noise ratio | intervals missing the truth | worst estimate error | on a bound | fit s |\n|---|---|---|---|---|---|---|---|\n");
    for &b in &bands {
        let (fits, bad) = of(Some(b));
        md += &format!(
            "\n{}",
            band_line(&band_label(rig_band(b)), &fits, bad.len(), reference_s)
        );
        failures.extend(bad);
        for f in &fits {
            per_dataset += &(dataset_line(&band_label(rig_band(b)), f) + "\n");
        }
    }
    md += &per_dataset;
    let fits: Vec<&Fitted> = results
        .iter()
        .filter_map(|(_, r)| r.as_ref().ok())
        .collect();
    md += &z_table(&fits);
    for (k, e) in failures.iter().enumerate() {
        md += &format!("{}- {e}\n", if k == 0 { "\nFailed:\n\n" } else { "" });
    }
    let out = env("RIG_OUT")
        .unwrap_or_else(|| format!("{}/target/every-size-rigs.md", env!("CARGO_MANIFEST_DIR")));
    std::fs::write(&out, &md).unwrap();
    println!("{md}\n(written to {out})");
}

/// The rig scaled to the motor: at 3.8 cm³ the configuration is coverage.rs's own, and at
/// 8× the size (s = 8: lengths × 2) the brake is × 16, the throttle's conductances and the
/// flow noise × 4, the torque noise × 8 and the speed noise × ½ (the laws of
/// tests/twin/sizes.rs, re-derived here from lengths).
#[test]
fn the_rig_scales_with_the_motor() {
    let base = twin::varied_config(7);
    assert_eq!(scaled_rig_config(7, 3.8e-6), base);
    assert_eq!(perturbed_motor_sized(7, 3.8e-6), twin::perturbed_motor(7));
    let big = scaled_rig_config(7, 8.0 * 3.8e-6);
    let l = 2.0f64; // length ratio
    let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-12;
    assert!(close(
        big.conditions.brake_nm_s_rad,
        base.conditions.brake_nm_s_rad * l.powi(4)
    ));
    assert!(close(
        big.conditions.c_throttle_m3_s_pa.0,
        base.conditions.c_throttle_m3_s_pa.0 * l * l
    ));
    assert!(close(big.noise.flow1_g_s, base.noise.flow1_g_s * l * l));
    assert!(close(big.noise.torque_nm, base.noise.torque_nm * l.powi(3)));
    assert!(close(big.noise.speed_rpm, base.noise.speed_rpm / l));
    assert_eq!(big.conditions.rate_hz, base.conditions.rate_hz);
    let m = perturbed_motor_sized(7, 8.0 * 3.8e-6);
    let m0 = twin::perturbed_motor(7);
    assert!(close(m.c_12, m0.c_12 * l * l) && close(m.inertia, m0.inertia * l.powi(5)));
    assert!(close(m.visc, m0.visc * l.powi(4)) && close(m.t_coulomb, m0.t_coulomb * l.powi(3)));
}

/// An error in its fit's own σ: an estimate 10 % low whose interval reaches
/// v·e^{1.96·0.05} above it has z = ln 0.9/0.05, and the chance that an estimate of that σ
/// errs by more than 10 % is Φ(ln 0.9/σ) + Φ(−ln 1.1/σ) (closed forms, Φ(1.96) = 0.975).
#[test]
fn errors_are_measured_in_the_fits_own_sigma() {
    assert!((normal_cdf(Z95) - 0.975).abs() < 1e-6);
    assert!((normal_cdf(0.0) - 0.5).abs() < 1e-7);
    let sd = 0.05;
    let e = Estimate {
        name: "c_12".into(),
        truth: 1.0,
        value: 0.9,
        lo: Some(0.9 * (-Z95 * 0.2_f64).exp()),
        hi: Some(0.9 * (Z95 * sd).exp()),
        bounds: None,
        closed: true,
    };
    assert!((e.sd_ln().unwrap() - sd).abs() < 1e-12);
    assert!((e.z().unwrap() - 0.9f64.ln() / sd).abs() < 1e-9);
    let p = normal_cdf(0.9f64.ln() / sd) + normal_cdf(-(1.1f64.ln()) / sd);
    assert!((e.p_beyond_10pct().unwrap() - p).abs() < 1e-12);
    // An open end on the truth's side gives no σ.
    let open = Estimate { hi: None, ..e };
    assert!(open.z().is_none());
}
