//! The written results of `vanefit predict` (docs/formats.md, "Contracts added later"):
//! `catalogue.csv`, `factors.csv`, `curves.csv`, `predict.md` and SVG figures, all written
//! atomically.
//!
//! Units at this edge: supply pressure in the unit asked for (column `p_supply_<unit>`,
//! a pressure unit of `p_port1` columns, docs/formats.md, "CSV recordings"; bar g unless
//! asked otherwise), speeds in rpm, power in W, torque in N·m, air consumption in l/s ANR
//! (the mass flow into port 1 divided by ρ0 = 1.185 kg/m³, ISO 8778; docs/model.md,
//! "Constants"). Every figure has its 95 % band in `<column>_lo` and `<column>_hi` (empty
//! when the fit gives no band); `extrapolated` is `true` for a pressure outside those the
//! fitted data covered (empty when the fit does not say which).

use crate::predict::{
    BandChoice, BandMethod, BandReason, Banded, PosteriorData, Prediction, PressurePrediction,
};
use crate::report::plot::{PlotError, COLOURS};
use crate::units::Unit;
use plotters::prelude::*;
use std::path::{Path, PathBuf};

/// Why the results could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PredictReportError {
    /// A file could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
    /// A figure could not be drawn.
    #[error(transparent)]
    Plot(#[from] PlotError),
}

/// How the supply pressure is shown: a unit of `p_port1` columns, and the atmosphere for
/// gauge units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PressureDisplay {
    /// The unit.
    pub unit: Unit,
    /// Atmosphere, Pa absolute.
    pub p_atm_pa: f64,
}

impl PressureDisplay {
    /// An absolute pressure (Pa) in the unit.
    pub fn value(&self, p_pa: f64) -> f64 {
        self.unit.from_si(p_pa, self.p_atm_pa)
    }

    /// The column name, `p_supply_<unit suffix>`.
    pub fn column(&self) -> String {
        format!("p_supply_{}", self.unit.suffix())
    }

    /// The unit for people: `bar g`, `mpa`, ….
    pub fn label(&self) -> String {
        self.unit.suffix().replace('_', " ")
    }

    /// A pressure as text: the value in the unit, shortest exact form.
    pub fn text(&self, p_pa: f64) -> String {
        short(self.value(p_pa))
    }
}

/// A catalogue column: name with unit, heading for people, conversion from SI.
struct Column {
    name: &'static str,
    heading: &'static str,
    from_si: fn(f64) -> f64,
}

fn rpm(v: f64) -> f64 {
    Unit::Rpm.from_si(v, 0.0)
}
fn same(v: f64) -> f64 {
    v
}
fn l_s_anr(v: f64) -> f64 {
    Unit::LSAnr.from_si(v, 0.0)
}

/// The catalogue's columns, in the order of `predict::ROW_FIGURES` (the names of
/// docs/formats.md, "Contracts added later").
const CATALOGUE: [Column; 7] = [
    Column {
        name: "free_speed_rpm",
        heading: "free speed [rpm]",
        from_si: rpm,
    },
    Column {
        name: "max_power_w",
        heading: "max. power [W]",
        from_si: same,
    },
    Column {
        name: "speed_at_max_power_rpm",
        heading: "speed at max. power [rpm]",
        from_si: rpm,
    },
    Column {
        name: "torque_at_max_power_nm",
        heading: "torque at max. power [N·m]",
        from_si: same,
    },
    Column {
        name: "stall_torque_nm",
        heading: "stall torque [N·m]",
        from_si: same,
    },
    Column {
        name: "air_at_max_power_l_s_anr",
        heading: "air at max. power [l/s ANR]",
        from_si: l_s_anr,
    },
    Column {
        name: "air_at_free_speed_l_s_anr",
        heading: "air at free speed [l/s ANR]",
        from_si: l_s_anr,
    },
];

/// The factors' columns, in the order of `predict::FACTORS`.
const FACTORS: [Column; 4] = [
    Column {
        name: "power",
        heading: "power (max. power)",
        from_si: same,
    },
    Column {
        name: "speed",
        heading: "speed (free speed)",
        from_si: same,
    },
    Column {
        name: "torque",
        heading: "torque (stall torque)",
        from_si: same,
    },
    Column {
        name: "air",
        heading: "air (at max. power)",
        from_si: same,
    },
];

/// The curves' columns: torque, power, air.
const CURVE: [Column; 3] = [
    Column {
        name: "torque_nm",
        heading: "shaft torque [N·m]",
        from_si: same,
    },
    Column {
        name: "power_w",
        heading: "shaft power [W]",
        from_si: same,
    },
    Column {
        name: "air_l_s_anr",
        heading: "air consumption [l/s ANR]",
        from_si: l_s_anr,
    },
];

/// A number for a CSV file: 7 significant digits, no exponent in the usual range.
fn csv_number(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let magnitude = v.abs().log10().floor() as i32;
    if !(-4..9).contains(&magnitude) {
        return format!("{v:.6e}");
    }
    let decimals = (6 - magnitude).max(0) as usize;
    format!("{v:.decimals$}")
}

/// The shortest text that reads back as `v` (for pressures as asked: 6.3, not 6.300000).
fn short(v: f64) -> String {
    let r = (v * 1e9).round() / 1e9;
    format!("{r}")
}

/// A value with its band for people, rounded to the band: two significant digits of the
/// band's half-width (four of the value when there is no band or it has no width).
fn with_band(b: &Banded, from_si: fn(f64) -> f64) -> String {
    let v = from_si(b.value);
    let band = b.band95.map(|[lo, hi]| (from_si(lo), from_si(hi)));
    let half = band.map_or(0.0, |(lo, hi)| 0.5 * (hi - lo).abs());
    let lead = if half > 0.0 {
        half
    } else {
        v.abs().max(1e-300) / 100.0
    };
    let decimals = (1 - lead.log10().floor() as i32).clamp(0, 9) as usize;
    match band {
        Some((lo, hi)) => format!("{v:.decimals$} [{lo:.decimals$}, {hi:.decimals$}]"),
        None => format!("{v:.decimals$}"),
    }
}

/// The extrapolation flag as the CSV writes it.
fn flag(p: &PressurePrediction) -> &'static str {
    match p.extrapolated {
        Some(true) => "true",
        Some(false) => "false",
        None => "",
    }
}

/// One CSV table: the header, then rows of cells.
fn csv(header: &[String], rows: &[Vec<String>]) -> String {
    let mut text = header.join(",") + "\n";
    for r in rows {
        text.push_str(&r.join(","));
        text.push('\n');
    }
    text
}

/// Cells of banded figures: the values, then each figure's lo and hi.
fn banded_cells(figures: &[Banded], columns: &[Column]) -> Vec<String> {
    let mut cells: Vec<String> = figures
        .iter()
        .zip(columns)
        .map(|(b, c)| csv_number((c.from_si)(b.value)))
        .collect();
    for (b, c) in figures.iter().zip(columns) {
        match b.band95 {
            Some([lo, hi]) => cells.extend([lo, hi].map(|v| csv_number((c.from_si)(v)))),
            None => cells.extend([String::new(), String::new()]),
        }
    }
    cells
}

/// The header of banded figures: the names, then `<name>_lo`, `<name>_hi` for each.
fn banded_header(columns: &[Column]) -> Vec<String> {
    let mut h: Vec<String> = columns.iter().map(|c| c.name.to_string()).collect();
    for c in columns {
        h.push(format!("{}_lo", c.name));
        h.push(format!("{}_hi", c.name));
    }
    h
}

/// `catalogue.csv`: one row per pressure (the first eight columns of docs/formats.md,
/// "Contracts added later", then the bands, `extrapolated` and the speed grid of the
/// maximum power in rpm).
pub fn catalogue_csv(pr: &Prediction, display: &PressureDisplay) -> String {
    let mut header = vec![display.column()];
    header.extend(banded_header(&CATALOGUE));
    header.extend(["extrapolated".to_string(), "speed_grid_rpm".to_string()]);
    let (shaft_header, shaft_cells) = shaft_columns(pr);
    header.extend(shaft_header);
    let grid = csv_number(rpm(pr.options.speed_grid_rad_s));
    let rows: Vec<Vec<String>> = pr
        .pressures
        .iter()
        .map(|p| {
            let mut r = vec![display.text(p.p_supply_pa)];
            r.extend(banded_cells(&p.figures, &CATALOGUE));
            r.extend([flag(p).to_string(), grid.clone()]);
            r.extend(shaft_cells.iter().cloned());
            r
        })
        .collect();
    csv(&header, &rows)
}

/// `factors.csv`: one row per pressure (the five columns of docs/formats.md, "Contracts
/// added later", then the bands and `extrapolated`).
pub fn factors_csv(pr: &Prediction, display: &PressureDisplay) -> String {
    let mut header = vec![display.column()];
    header.extend(banded_header(&FACTORS));
    header.push("extrapolated".into());
    let rows: Vec<Vec<String>> = pr
        .pressures
        .iter()
        .map(|p| {
            let mut r = vec![display.text(p.p_supply_pa)];
            r.extend(banded_cells(&p.factors, &FACTORS));
            r.push(flag(p).to_string());
            r
        })
        .collect();
    csv(&header, &rows)
}

/// `curves.csv`: one row per pressure and speed.
pub fn curves_csv(pr: &Prediction, display: &PressureDisplay) -> String {
    let mut header = vec![display.column(), "speed_rpm".into()];
    header.extend(banded_header(&CURVE));
    header.push("extrapolated".into());
    let (shaft_header, shaft_cells) = shaft_columns(pr);
    header.extend(shaft_header);
    let mut rows = Vec::new();
    for p in &pr.pressures {
        for c in &p.curve {
            let mut r = vec![display.text(p.p_supply_pa), csv_number(rpm(c.speed_rad_s))];
            r.extend(banded_cells(&[c.torque_nm, c.power_w, c.air_kg_s], &CURVE));
            r.push(flag(p).to_string());
            r.extend(shaft_cells.iter().cloned());
            rows.push(r);
        }
    }
    csv(&header, &rows)
}

/// A Markdown table of banded figures, one row per pressure (an asterisk marks an
/// extrapolation).
fn markdown_table(
    pr: &Prediction,
    display: &PressureDisplay,
    columns: &[Column],
    cells: fn(&PressurePrediction) -> &[Banded],
) -> String {
    let mut text = format!("| p_supply [{}] |", display.label());
    for c in columns {
        text.push_str(&format!(" {} |", c.heading));
    }
    text.push_str(&format!("\n|---:|{}\n", "---:|".repeat(columns.len())));
    for p in &pr.pressures {
        let mark = if p.extrapolated == Some(true) {
            " *"
        } else {
            ""
        };
        text.push_str(&format!("| {}{mark} |", display.text(p.p_supply_pa)));
        for (b, c) in cells(p).iter().zip(columns) {
            text.push_str(&format!(" {} |", with_band(b, c.from_si)));
        }
        text.push('\n');
    }
    text
}

/// Which shaft a geared motor's figures are for, for people (`None` without a gearbox,
/// where the motor's shaft is the only one).
pub fn shaft_note(pr: &Prediction) -> Option<String> {
    let g = pr.gear.as_ref()?;
    Some(format!(
        "Figures at the gearbox's OUTPUT shaft, as the page printed them ({}). The motor shaft turns {} times as fast, with torque ÷ {:.4} (η·G) and power ÷ {:.4} (η); air is the same on either shaft.",
        g.describe(),
        g.ratio,
        g.efficiency * g.ratio,
        g.efficiency
    ))
}

/// The columns a geared prediction's CSV rows end with: the shaft, the ratio and the
/// efficiency (none without a gearbox, so that an ungeared motor's files keep their
/// columns).
fn shaft_columns(pr: &Prediction) -> (Vec<String>, Vec<String>) {
    match &pr.gear {
        None => (Vec::new(), Vec::new()),
        Some(g) => (
            ["shaft", "gear_ratio", "gear_efficiency"]
                .map(String::from)
                .to_vec(),
            vec![
                "output".into(),
                csv_number(g.ratio),
                csv_number(g.efficiency),
            ],
        ),
    }
}

/// The catalogue and the factors as Markdown tables (what the command line prints), after
/// the shaft of a geared motor's figures.
pub fn tables_markdown(pr: &Prediction, display: &PressureDisplay) -> String {
    let shaft = shaft_note(pr).map_or(String::new(), |n| format!("{n}\n\n"));
    format!(
        "{shaft}{}\nCorrection factors relative to {} {}:\n\n{}",
        markdown_table(pr, display, &CATALOGUE, |p| &p.figures),
        display.text(pr.options.reference_pa),
        display.label(),
        markdown_table(pr, display, &FACTORS, |p| &p.factors),
    )
}

/// The notes every output carries: grid, what the factors are, the band's basis and what
/// it leaves out, extrapolation, nozzle and atmosphere.
pub fn notes(pr: &Prediction, display: &PressureDisplay) -> Vec<String> {
    let o = &pr.options;
    let mut notes = figure_notes(pr, display);
    if pr.uncertainty.basis == crate::predict::uncertainty::BandBasis::Independent {
        notes.push(
            "WARNING: the parameters are treated as INDEPENDENT (no covariance in the fit file): where they trade off, the bands are wrong, too wide or too narrow."
                .into(),
        );
    }
    notes.extend(pr.fit_warnings.iter().cloned());
    notes.extend(resting_notes(pr, display));
    notes.extend(band_notes(pr));
    notes.extend(uncovered_notes(pr));
    notes.push(supply_range_note(pr, display));
    notes.push(match o.nozzle {
        Some(n) => format!(
            "With an extra nozzle of C = {:e} m3/(s*Pa) in series at the {}.",
            n.c_m3_s_pa,
            n.port.name()
        ),
        None => "No extra nozzle.".into(),
    });
    notes.push(format!("Atmosphere {:.0} Pa.", o.p_atm_pa));
    notes
}

/// What the figures are: the speed grid of maximum power, the operating points of the
/// other figures, and what each factor compares.
fn figure_notes(pr: &Prediction, display: &PressureDisplay) -> Vec<String> {
    let o = &pr.options;
    vec![
        format!(
            "Maximum power is exact on a grid of {} rpm: the grid speed of largest power near \
             the continuous optimum of P(ω) = T(ω)·ω; torque and air at maximum power are at \
             that grid speed.",
            short(rpm(o.speed_grid_rad_s))
        ),
        "Free speed: shaft torque zero (no load). Stall torque: standstill, less the full \
         friction at rest. Air: mass flow into port 1 in l/s ANR (ρ0 = 1.185 kg/m³)."
            .into(),
        format!(
            "Factors relative to {} {}: power = max. power, speed = free speed, torque = stall \
             torque, air = air consumption at max. power.",
            display.text(o.reference_pa),
            display.label()
        ),
    ]
}

/// What the band leaves out or covers only by a stated spread: parameters neither
/// sampled nor in the covariance, those held fixed, discovered terms' coefficients.
fn uncovered_notes(pr: &Prediction) -> Vec<String> {
    let mut notes = Vec::new();
    let sampled: &[String] = pr.bands.used_samples().map_or(&[], |s| &s.names);
    for (name, why) in &pr.uncertainty.uncovered {
        if !sampled.contains(name) {
            notes.push(format!("The band does not cover {name}: {why}."));
        }
    }
    if let (Some(f), false) = (
        pr.uncertainty.spread_factor,
        pr.uncertainty.spread.is_empty(),
    ) {
        notes.push(format!(
            "The band covers {} (held fixed or not identifiable) as uncertain within ×/÷ {f} (95 %, independent; --fixed-spread).",
            pr.uncertainty.spread.join(", ")
        ));
    }
    if !pr.fixed.is_empty() {
        notes.push(format!(
            "The band does not cover the parameters the fit held fixed (taken as exact): {}.",
            pr.fixed.join(", ")
        ));
    }
    if pr.discovered_terms > 0 {
        notes.push(format!(
            "The band does not cover the coefficients of the {} discovered term(s).",
            pr.discovered_terms
        ));
    }
    notes
}

/// The supply pressures the fitted data covered and which asked pressures lie outside
/// them (extrapolated), or that the fit file does not say.
fn supply_range_note(pr: &Prediction, display: &PressureDisplay) -> String {
    let Some([lo, hi]) = pr.supply_range_pa else {
        return "The fit file does not say which supply pressures its data covered: \
                extrapolation cannot be flagged."
            .into();
    };
    let out: Vec<String> = pr
        .pressures
        .iter()
        .filter(|p| p.extrapolated == Some(true))
        .map(|p| display.text(p.p_supply_pa))
        .collect();
    let verdict = if out.is_empty() {
        "every asked pressure lies within it".to_string()
    } else {
        format!(
            "EXTRAPOLATED (marked *): {} {}",
            out.join(", "),
            display.label()
        )
    };
    format!(
        "The fitted data covered supply pressures {} to {} {} (± {:.0} kPa, the \
         pressure sensor's tolerance); {verdict}.",
        short((display.value(lo) * 1e4).round() / 1e4),
        short((display.value(hi) * 1e4).round() / 1e4),
        display.label(),
        pr.range_tolerance_pa / 1e3
    )
}

/// One note per pressure naming the figures whose band rests on the motor prior, the
/// share of the band's variance that knowing the prior-resting parameters would remove,
/// the largest of them alone, and the measurements that would pin them: "At 3 bar g, 3
/// bands rest on the motor prior more than on the data: stall torque 81 % (t_coulomb 74 %),
/// … One more measurement would pin them: the torque curve (or stall torque) at a second
/// supply pressure."
pub fn resting_notes(pr: &Prediction, display: &PressureDisplay) -> Vec<String> {
    let mut out = Vec::new();
    for p in &pr.pressures {
        let here: Vec<_> = pr
            .resting
            .iter()
            .filter(|r| r.p_supply_pa == p.p_supply_pa)
            .collect();
        if here.is_empty() {
            continue;
        }
        let figures: Vec<String> = here
            .iter()
            .map(|r| {
                let on: Vec<String> = r
                    .parameters
                    .iter()
                    .take(2)
                    .map(|(n, s)| format!("{n} {:.0} %", 100.0 * s))
                    .collect();
                let on = if on.is_empty() {
                    "several, none alone above 5 %".to_string()
                } else {
                    on.join(", ")
                };
                format!(
                    "{} {:.0} % ({on})",
                    r.figure.replace('_', " "),
                    100.0 * r.prior_share
                )
            })
            .collect();
        let mut pins: Vec<&str> = here
            .iter()
            .filter(|r| !r.parameters.is_empty())
            .map(|r| r.pinned_by())
            .collect();
        pins.sort_unstable();
        pins.dedup();
        out.push(format!(
            "At {} {}, {} band(s) rest on the motor prior more than on the data (the share of each band's variance that knowing the parameters resting on their prior would remove; in brackets the largest of them alone): {}. What would pin them: {}.",
            display.text(p.p_supply_pa),
            display.label(),
            here.len(),
            figures.join(", "),
            pins.join("; ")
        ));
    }
    out
}

/// The notes on which method made the bands (every band of a prediction is made by one
/// method), why, and how well the samples converged.
pub fn band_notes(pr: &Prediction) -> Vec<String> {
    let b = &pr.bands;
    if let Some(s) = b.used_samples() {
        return sampled_band_notes(pr, s);
    }
    let mut out = vec![
        format!("{}.", capitalised(&b.statement())),
        format!("{}.", pr.uncertainty.basis.describe()),
    ];
    let fix = match (&b.reason, b.choice) {
        (_, BandChoice::Delta) => "--bands auto or samples bands from posterior samples instead",
        (BandReason::NotConverged, _) => {
            "more steps (--steps) may let the samples converge; --bands samples uses them anyway"
        }
        _ => "give the fit's dataset (--data) to band from posterior samples",
    };
    match (&b.delta_unreliable, &b.sampling) {
        // Samples were had: the fit file's reasons qualify the fallback.
        (Some(w), Some(_)) => out.push(format!(
            "The fit file says the posterior is not close to Gaussian here ({w}), where \
             delta-method bands may be off: {fix}."
        )),
        (Some(w), None) => out.push(format!(
            "The delta method is NOT to be trusted here ({w}): the bands above may be far \
             off; {fix}."
        )),
        (None, _) => {}
    }
    if b.sampling.is_some() {
        out.push(
            "The samples that did not converge are summarised under \"Posterior samples\"; \
             none was propagated through the figures (convergence is decided first)."
                .to_string(),
        );
    }
    out
}

/// `text` with its first letter in upper case.
fn capitalised(text: &str) -> String {
    let mut c = text.chars();
    c.next()
        .map(|f| f.to_uppercase().chain(c).collect())
        .unwrap_or_default()
}

/// The notes on bands made from the posterior samples `s`: why samples, how they were
/// drawn, whether they converged, and what they leave out or found amiss.
fn sampled_band_notes(pr: &Prediction, s: &crate::predict::PosteriorSummary) -> Vec<String> {
    let b = &pr.bands;
    let why = match &b.delta_unreliable {
        Some(w) => format!(
            " (--bands {}; the delta method is not to be trusted here: {w})",
            b.choice.name()
        ),
        _ => format!(" (--bands {})", b.choice.name()),
    };
    let mut out = vec![
        format!("{}.", capitalised(&b.statement())),
        format!(
            "EVERY band is made from POSTERIOR SAMPLES{why}: the 2.5 and 97.5 percentiles \
             of each figure over {} samples of {} ({} {} × {} steps after {} burn-in, \
             {}, seed {}, acceptance {:.2}); the value is the figure at the estimate.",
            s.draws - s.failed_draws,
            s.names.join(", "),
            s.walkers,
            sampler_words(s.sampler).0,
            s.steps,
            s.burn_in,
            sampler_words(s.sampler).1,
            s.seed,
            s.acceptance
        ),
        convergence_note(s),
    ];
    let outside = outside_own_band(pr);
    if outside > 0 {
        out.push(format!(
            "{outside} figure(s) at the estimate lie OUTSIDE their own band: the \
             posterior's mass lies away from the best fit (a lopsided valley, or a \
             parameter the data do not pin and the prior does not hold)."
        ));
    }
    if s.failed_draws > 0 {
        out.push(format!(
            "{} of {} samples gave no figures (the motor fails at some pressure) and \
             are left out.",
            s.failed_draws, s.draws
        ));
    }
    if !s.spread.is_empty() {
        out.push(format!(
            "{} not sampled: drawn for each sample within the stated spread.",
            s.spread.join(", ")
        ));
    }
    out
}

/// What drew the samples: (its units, "walkers" or "chains"; its description and why).
fn sampler_words(s: crate::predict::Sampler) -> (&'static str, String) {
    use crate::predict::{Sampler, TRANSPORT_K_HAT_LIMIT};
    match s {
        Sampler::Laplace { k_hat } => (
            "chains",
            format!(
                "Metropolis–Hastings from the fit's Laplace approximation and whitened random \
                 walks, as the posterior is close to that approximation: importance weights' \
                 k̂ {k_hat:.2} < 0.7"
            ),
        ),
        Sampler::Transport {
            laplace_k_hat,
            k_hat,
        } => (
            "chains",
            format!(
                "Metropolis–Hastings in the coordinates of a quadratic transport map learnt \
                 from a pilot ensemble, which straightens the posterior's curved valley \
                 (independence moves from a t there, importance weights' k̂ {k_hat:.2}, and \
                 whitened random walks), as the posterior is far from the fit's Laplace \
                 approximation{}",
                match laplace_k_hat {
                    Some(k) if k.is_finite() => format!(" (its weights' k̂ {k:.2} ≥ 0.7)"),
                    Some(_) => " (some of its draws lie outside the support)".to_string(),
                    None => String::new(),
                }
            ),
        ),
        Sampler::Ensemble {
            k_hat,
            transport_k_hat,
        } => (
            "walkers",
            format!(
                "affine-invariant ensemble of differential-evolution and stretch moves{}{}",
                match k_hat {
                    Some(k) if k.is_finite() => format!(
                        ", as the posterior is far from the fit's Laplace approximation \
                         (importance weights' k̂ {k:.2} ≥ 0.7)"
                    ),
                    Some(_) => ", as the posterior is far from the fit's Laplace \
                         approximation (some of its draws lie outside the support)"
                        .to_string(),
                    None => String::new(),
                },
                match transport_k_hat {
                    Some(k) => format!(
                        ", and a quadratic transport map did not straighten it (k̂ {k:.2} > \
                         {TRANSPORT_K_HAT_LIMIT})"
                    ),
                    None => String::new(),
                }
            ),
        ),
    }
}

/// Whether the samples converged by the usual rules, with their largest R̂ and smallest
/// effective sample size.
fn convergence_note(s: &crate::predict::PosteriorSummary) -> String {
    let (worst_rhat, least_ess) = s.worst();
    if s.converged() {
        format!(
            "The samples converged: largest R̂ {worst_rhat:.3} (< 1.01), smallest \
             effective sample size {least_ess:.0} (≥ 400)."
        )
    } else {
        format!(
            "The samples did NOT converge by the usual rules (R̂ < 1.01, effective \
             sample size ≥ 400): largest R̂ {worst_rhat:.3}, smallest effective sample \
             size {least_ess:.0}; run longer (--steps) before trusting the bands."
        )
    }
}

/// Catalogue figures and factors (all pressures) whose value at the estimate lies outside
/// their band.
fn outside_own_band(pr: &Prediction) -> usize {
    pr.pressures
        .iter()
        .flat_map(|p| p.figures.iter().chain(&p.factors))
        .filter(|b| {
            b.band95
                .is_some_and(|[lo, hi]| b.value < lo.min(hi) || b.value > hi.max(lo))
        })
        .count()
}

/// The posterior samples' table in Markdown (empty when the bands are delta bands):
/// each parameter's quantiles, R̂ and effective sample sizes.
pub fn sampling_markdown(pr: &Prediction) -> String {
    let Some(s) = &pr.bands.sampling else {
        return String::new();
    };
    let mut t = String::from("## Posterior samples\n\n");
    if pr.bands.used_samples().is_none() {
        t.push_str(
            "Not used for the bands: they did not converge (every R̂ < 1.01 and ESS ≥ 400 \
             is needed).\n\n",
        );
    }
    t.push_str(
        "| parameter | 2.5 % | median | 97.5 % | R̂ | ESS bulk | ESS tail |\n\
         |---|---:|---:|---:|---:|---:|---:|\n",
    );
    for ((n, q), d) in s.names.iter().zip(&s.quantiles).zip(&s.diagnostics) {
        t.push_str(&format!(
            "| {n} | {:.4e} | {:.4e} | {:.4e} | {:.3} | {:.0} | {:.0} |\n",
            q[0], q[1], q[2], d.rhat, d.ess_bulk, d.ess_tail
        ));
    }
    t.push('\n');
    t
}

/// `sampling.json`: the samples' settings, quantiles and diagnostics (`null` for delta
/// bands).
pub fn sampling_json(pr: &Prediction) -> serde_json::Value {
    let b = &pr.bands;
    let sampling = b.sampling.as_ref().map(|s| {
        let params: serde_json::Map<String, serde_json::Value> = s
            .names
            .iter()
            .zip(&s.quantiles)
            .zip(&s.diagnostics)
            .map(|((n, q), d)| {
                (
                    n.clone(),
                    serde_json::json!({
                        "q025": q[0], "median": q[1], "q975": q[2],
                        "rhat": d.rhat, "ess_bulk": d.ess_bulk, "ess_tail": d.ess_tail,
                    }),
                )
            })
            .collect();
        let (rhat_max, ess_min) = s.worst();
        serde_json::json!({
            "walkers": s.walkers, "steps": s.steps, "burn_in": s.burn_in, "seed": s.seed,
            "rhat_max": rhat_max, "ess_min": ess_min,
            "sampler": match s.sampler {
                crate::predict::Sampler::Laplace { .. } => "laplace_chains",
                crate::predict::Sampler::Ensemble { .. } => "ensemble",
                crate::predict::Sampler::Transport { .. } => "transport_chains",
            },
            "laplace_k_hat": match s.sampler {
                crate::predict::Sampler::Laplace { k_hat } => Some(k_hat),
                crate::predict::Sampler::Ensemble { k_hat, .. } => k_hat.filter(|k| k.is_finite()),
                crate::predict::Sampler::Transport { laplace_k_hat, .. } => {
                    laplace_k_hat.filter(|k| k.is_finite())
                }
            },
            "transport_k_hat": match s.sampler {
                crate::predict::Sampler::Transport { k_hat, .. } => Some(k_hat),
                crate::predict::Sampler::Ensemble { transport_k_hat, .. } => transport_k_hat,
                _ => None,
            },
            "acceptance": s.acceptance, "draws": s.draws, "failed_draws": s.failed_draws,
            "propagated": s.draws > 0,
            "converged": s.converged(), "spread": s.spread, "parameters": params,
        })
    });
    serde_json::json!({
        "method": match b.method { BandMethod::Delta => "delta", BandMethod::Samples => "samples" },
        "asked": b.choice.name(),
        "reason": b.statement(),
        "dataset": match &b.data {
            Some(PosteriorData::At(at)) => serde_json::json!({ "found": true, "where": at }),
            Some(PosteriorData::Missing(why)) => serde_json::json!({ "found": false, "where": why }),
            None => serde_json::Value::Null,
        },
        "delta_unreliable": b.delta_unreliable,
        "sampling": sampling,
    })
}

/// `predict.md`: a title, the tables, the notes and the figures' names.
pub fn markdown(pr: &Prediction, display: &PressureDisplay, source: &str) -> String {
    let mut text = format!(
        "# Predicted performance\n\nFrom `{source}`. Values with their 95 % bands \
         [lo, hi].\n\n{}\n## Notes\n\n",
        tables_markdown(pr, display)
    );
    for n in notes(pr, display) {
        text.push_str(&format!("- {n}\n"));
    }
    let sampled = sampling_markdown(pr);
    if !sampled.is_empty() {
        text.push('\n');
        text.push_str(&sampled);
    }
    text.push_str(
        "\nFigures: `torque.svg`, `power.svg`, `air.svg` (against speed, one curve per \
         pressure with its band shaded) and `factors.svg`.\n",
    );
    text
}

/// Writes every output into `dir` (which exists), telling `on_written` of each file.
pub fn write(
    pr: &Prediction,
    display: &PressureDisplay,
    source: &str,
    dir: &Path,
    on_written: &mut dyn FnMut(&Path),
) -> Result<(), PredictReportError> {
    let mut put = |name: &str, text: &str| {
        let path = dir.join(name);
        crate::io::write_atomic(&path, text.as_bytes()).map_err(|source| {
            PredictReportError::Write {
                path: path.clone(),
                source,
            }
        })?;
        on_written(&path);
        Ok::<_, PredictReportError>(())
    };
    put("catalogue.csv", &catalogue_csv(pr, display))?;
    put("factors.csv", &factors_csv(pr, display))?;
    put("curves.csv", &curves_csv(pr, display))?;
    put("predict.md", &markdown(pr, display, source))?;
    let bands = serde_json::to_string_pretty(&sampling_json(pr)).unwrap_or_default();
    put("bands.json", &bands)?;
    for (k, c) in CURVE.iter().enumerate() {
        let series = pr
            .pressures
            .iter()
            .map(|p| BandSeries {
                name: format!(
                    "{} {}{}",
                    display.text(p.p_supply_pa),
                    display.label(),
                    if p.extrapolated == Some(true) {
                        " (extrapolated)"
                    } else {
                        ""
                    }
                ),
                points: p
                    .curve
                    .iter()
                    .map(|pt| {
                        let b = [pt.torque_nm, pt.power_w, pt.air_kg_s][k];
                        banded_point(rpm(pt.speed_rad_s), &b, c.from_si)
                    })
                    .collect(),
            })
            .collect::<Vec<_>>();
        let title = format!("Predicted {} against speed", c.heading);
        let svg = band_chart(&title, "speed [rpm]", c.heading, &series)?;
        put(
            &format!("{}.svg", c.name.split('_').next().unwrap_or(c.name)),
            &svg,
        )?;
    }
    let factors = FACTORS
        .iter()
        .enumerate()
        .map(|(k, c)| BandSeries {
            name: c.heading.to_string(),
            points: pr
                .pressures
                .iter()
                .map(|p| banded_point(display.value(p.p_supply_pa), &p.factors[k], same))
                .collect(),
        })
        .collect::<Vec<_>>();
    let title = format!(
        "Correction factors relative to {} {}",
        display.text(pr.options.reference_pa),
        display.label()
    );
    let x = format!("supply pressure [{}]", display.label());
    let svg = band_chart(&title, &x, "factor", &factors)?;
    put("factors.svg", &svg)
}

/// One point of a banded curve: (x, y, lo, hi) in display units (lo = hi = y without band).
fn banded_point(x: f64, b: &Banded, from_si: fn(f64) -> f64) -> (f64, f64, f64, f64) {
    let y = from_si(b.value);
    let [lo, hi] = b.band95.map_or([y, y], |[l, h]| [from_si(l), from_si(h)]);
    (x, y, lo, hi)
}

/// A curve with its band, for [`band_chart`].
struct BandSeries {
    name: String,
    points: Vec<(f64, f64, f64, f64)>,
}

/// A tick label: at most four decimals, trailing zeros dropped (2000, not 2000.0).
fn tick(v: f64) -> String {
    if v != 0.0 && !(1e-3..1e6).contains(&v.abs()) {
        return format!("{v:.1e}");
    }
    let s = format!("{v:.4}");
    s.trim_end_matches('0').trim_end_matches('.').to_string()
}

/// An SVG chart of curves, each with its band as a shaded area under the line (the shared
/// `report::plot` draws lines and markers only; this is the one chart that shades).
/// Width of the legend strip beside a band chart, px.
const LEGEND_W: u32 = 190;

/// The legend of a band chart in its own strip: one line and name per series, then what the
/// shading is.
fn side_legend<DB: DrawingBackend>(
    strip: &DrawingArea<DB, plotters::coord::Shift>,
    series: &[BandSeries],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let font = ("sans-serif", 13).into_font().color(&BLACK);
    let mut y = 56;
    for (k, s) in series.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()];
        strip.draw(&Rectangle::new(
            [(6, y - 7), (28, y + 7)],
            colour.mix(0.25).filled(),
        ))?;
        strip.draw(&PathElement::new(
            vec![(6, y), (28, y)],
            colour.stroke_width(2),
        ))?;
        strip.draw(&Text::new(s.name.clone(), (34, y - 7), font.clone()))?;
        y += 22;
    }
    strip.draw(&Text::new("shaded: 95 % band", (6, y + 4), font))?;
    Ok(())
}

fn band_chart(
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[BandSeries],
) -> Result<String, PlotError> {
    let err = |e: &dyn std::fmt::Display| PlotError::Draw(e.to_string());
    let all = series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, _, lo, hi) in all.filter(|p| p.0.is_finite() && p.2.is_finite() && p.3.is_finite()) {
        (x0, x1) = (x0.min(x), x1.max(x));
        (y0, y1) = (y0.min(lo), y1.max(hi));
    }
    if x1.is_nan() || x0.is_nan() || x1 <= x0 {
        (x0, x1) = (x0.min(0.0) - 1.0, x1.max(0.0) + 1.0);
    }
    if y1.is_nan() || y0.is_nan() || y1 <= y0 {
        (y0, y1) = (y0.min(0.0) - 1.0, y1.max(0.0) + 1.0);
    }
    let pad = 0.04 * (y1 - y0);
    let mut buf = String::new();
    {
        let root = SVGBackend::with_string(&mut buf, (720 + LEGEND_W, 460)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| err(&e))?;
        // The legend gets its own strip right of the plot, so it never covers a curve.
        let (root, strip) = root.split_horizontally(720);
        side_legend(&strip, series).map_err(|e| err(&e))?;
        let mut cc = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 18))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(64)
            .build_cartesian_2d(x0..x1, (y0 - pad)..(y1 + pad))
            .map_err(|e| err(&e))?;
        let fmt = |v: &f64| tick(*v);
        cc.configure_mesh()
            .x_desc(x_label)
            .y_desc(y_label)
            .x_label_formatter(&fmt)
            .y_label_formatter(&fmt)
            .axis_desc_style(("sans-serif", 15))
            .label_style(("sans-serif", 13))
            .light_line_style(RGBColor(238, 238, 238))
            .draw()
            .map_err(|e| err(&e))?;
        for (k, s) in series.iter().enumerate() {
            let colour = COLOURS[k % COLOURS.len()];
            let upper = s.points.iter().map(|p| (p.0, p.3));
            let lower = s.points.iter().rev().map(|p| (p.0, p.2));
            let area: Vec<(f64, f64)> = upper.chain(lower).collect();
            cc.draw_series(std::iter::once(Polygon::new(
                area,
                colour.mix(0.25).filled(),
            )))
            .map_err(|e| err(&e))?;
            let line: Vec<(f64, f64)> = s.points.iter().map(|p| (p.0, p.1)).collect();
            cc.draw_series(LineSeries::new(line, colour.stroke_width(2)))
                .map_err(|e| err(&e))?;
        }
        root.present().map_err(|e| err(&e))?;
    }
    Ok(buf)
}
