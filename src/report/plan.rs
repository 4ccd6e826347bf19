//! The written results of `vanefit plan` (docs/plan.md): `plan.md`, for people and the
//! technician who runs the measurement, and `plan.json`, the same in SI for programs; both
//! written atomically.
//!
//! Units at this edge, as `predict`'s: supply pressure in the unit asked for, speeds in
//! rpm, power in W, torque in N·m, air in l/s ANR, conductances in m³/(s·Pa), rig time in
//! hours. `plan.json` holds SI values under names that carry their unit.

use crate::plan::{Assessed, Candidate, Plan, RigSettings, Target, TargetFigure};
use crate::report::predict::PressureDisplay;
use crate::units::{Quantity, Unit};
use serde_json::{json, Value};
use std::path::{Path, PathBuf};

/// Why the results could not be written.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum PlanReportError {
    /// A file could not be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file.
        path: PathBuf,
        /// Why.
        source: std::io::Error,
    },
}

/// A figure's value for people: its unit and the conversion from SI.
fn unit_of(f: TargetFigure) -> (&'static str, Unit) {
    match f.quantity() {
        Quantity::Speed => ("rpm", Unit::Rpm),
        Quantity::Flow1 => ("l/s ANR", Unit::LSAnr),
        Quantity::Torque => ("N·m", Unit::Nm),
        _ => ("W", Unit::W),
    }
}

/// `v` rounded to two significant digits of `scale` (four of `v` without one).
fn rounded(v: f64, scale: f64) -> String {
    let lead = if scale > 0.0 {
        scale
    } else {
        v.abs().max(1e-300) / 100.0
    };
    let decimals = (1 - lead.log10().floor() as i32).clamp(0, 9) as usize;
    format!("{v:.decimals$}")
}

/// A band for people, rounded to its own half-width.
fn band_text(b: [f64; 2], scale: f64) -> String {
    format!("[{}, {}]", rounded(b[0], scale), rounded(b[1], scale))
}

/// "datasheet at 4 bar g", "pressure_ramp".
pub fn candidate_name(c: &Candidate, display: &PressureDisplay) -> String {
    match c.at_pa {
        Some(p) => format!(
            "{} at {} {}",
            c.kind.name(),
            display.text(p),
            display.label()
        ),
        None => c.kind.name().to_string(),
    }
}

/// Where a target sits: "4 bar g, max_power" or "4 bar g, 1200 rpm, torque".
fn target_name(t: &Target, display: &PressureDisplay) -> String {
    let p = format!("{} {}", display.text(t.p_supply_pa), display.label());
    match t.speed_rad_s {
        Some(w) => format!(
            "{p}, {} rpm, {}",
            rounded(Unit::Rpm.from_si(w, 0.0), 0.0),
            t.figure.name()
        ),
        None => format!("{p}, {}", t.figure.name()),
    }
}

/// The ranking as a Markdown table.
pub fn ranking_markdown(plan: &Plan, display: &PressureDisplay) -> String {
    let mut s = String::from(
        "| rank | candidate | cost [h] | V: variance removed | V per hour | D: information [nats] | mean band shrinkage | largest |\n\
         |---:|---|---:|---:|---:|---:|---:|---|\n",
    );
    for (i, a) in plan.ranked.iter().enumerate() {
        let best = a
            .shrinkage
            .iter()
            .enumerate()
            .max_by(|x, y| x.1.total_cmp(y.1))
            .map_or(String::new(), |(j, v)| {
                format!(
                    "{:.0} % ({})",
                    100.0 * v,
                    target_name(&plan.targets[j], display)
                )
            });
        s += &format!(
            "| {} | {} | {} | {:.1} % | {:.1} %/h | {:.2} | {:.1} % | {} |\n",
            i + 1,
            candidate_name(&a.candidate, display),
            a.candidate.cost_h,
            100.0 * a.v_reduction,
            100.0 * a.v_per_hour(),
            a.d_gain_nats,
            100.0 * a.mean_shrinkage(),
            best
        );
    }
    s
}

/// The settings a technician runs, one bullet each.
fn rig_markdown(r: &RigSettings, display: &PressureDisplay) -> String {
    let p = |v: f64| format!("{} {}", display.text(v), display.label());
    let mut s = if r.p_supply_pa[0] == r.p_supply_pa[1] {
        format!("- supply pressure: {}\n", p(r.p_supply_pa[0]))
    } else {
        format!(
            "- supply pressure: ramp from {} to {}, slowly enough to stay steady\n",
            p(r.p_supply_pa[0]),
            p(r.p_supply_pa[1])
        )
    };
    if let Some([a, b]) = r.speeds_rad_s {
        let rpm = |w| rounded(Unit::Rpm.from_si(w, 0.0), 0.0);
        s += &format!(
            "- imposed speeds: {} to {} rpm, evenly spaced (motor shaft)\n",
            rpm(a),
            rpm(b)
        );
    }
    if let Some([a, b]) = r.throttle_m3_s_pa {
        s += &format!("- outlet throttle: sonic conductance from {a:.3e} down to {b:.3e} m³/(s·Pa), log-spaced; shaft free\n");
    }
    if let Some([a, b]) = r.load_nm {
        s += &format!(
            "- brake torque: step from {} to {} N·m (motor shaft)\n",
            rounded(a, b / 10.0),
            rounded(b, b / 10.0)
        );
    }
    s += &format!(
        "- points: {}, {} reading(s) averaged at each; about {:.1} min of recording\n- record: {}\n",
        r.points,
        r.readings,
        r.duration_s / 60.0,
        r.records
    );
    s
}

/// One detailed candidate: settings, bands before and after, parameters' spread.
fn detail_markdown(plan: &Plan, rank: usize, a: &Assessed, display: &PressureDisplay) -> String {
    let mut s = format!(
        "### {}. {} ({} h)\n\n{}\n| operating point | now [95 %] | after, expected [95 %] | band shrinks by |\n|---|---|---|---:|\n",
        rank,
        candidate_name(&a.candidate, display),
        a.candidate.cost_h,
        rig_markdown(&a.candidate.rig, display)
    );
    for ((t, after), k) in plan.targets.iter().zip(&a.band_after).zip(&a.shrinkage) {
        let (unit, u) = unit_of(t.figure);
        let c = |v: f64| u.from_si(v, 0.0);
        let half = 0.5 * (c(t.band_before[1]) - c(t.band_before[0])).abs();
        s += &format!(
            "| {} [{unit}] | {} {} | {} | {:.0} % |\n",
            target_name(t, display),
            rounded(c(t.value), half),
            band_text([c(t.band_before[0]), c(t.band_before[1])], half),
            band_text([c(after[0]), c(after[1])], half),
            100.0 * k
        );
    }
    s += "\n| parameter | ×/÷ now (95 %) | ×/÷ after |\n|---|---:|---:|\n";
    for ((n, b), af) in plan.parameters.iter().zip(&plan.sd_before).zip(&a.sd_after) {
        let f = |sd: f64| (crate::predict::Z95 * sd).exp();
        s += &format!("| {n} | {:.3} | {:.3} |\n", f(*b), f(*af));
    }
    s + "\n"
}

/// What the ranking rests on, in words.
pub fn notes(plan: &Plan) -> Vec<String> {
    let mut out = vec![format!(
        "Linearised about the estimate: {}; each candidate adds its Fisher information GᵀΣ⁻¹G (its simulated sensitivities, the rig's sensor noise for the motor's size or a page's 2 % reading tolerance) added in the curvature's units, and the bands after are the delta method's with the updated covariance (the stretch to each profile interval's width taken to persist). Ranked by V (the mean relative variance removed at the operating points) per hour of rig time.",
        plan.basis.describe()
    )];
    if let Some(why) = &plan.not_gaussian {
        out.push(format!("WARNING: the posterior is far from Gaussian ({why}): the expected shrinkage is a linear guess; refit after the measurement to know (posterior samples are not used by the plan)."));
    }
    if !plan.uncovered.is_empty() {
        let u: Vec<String> = plan
            .uncovered
            .iter()
            .map(|(n, w)| format!("{n} ({w})"))
            .collect();
        out.push(format!(
            "Not in the bands (as in predict's): {}.",
            u.join(", ")
        ));
    }
    for (c, why) in &plan.dropped {
        out.push(format!("Left out: {c}: {why}."));
    }
    if plan.gear.is_some() {
        out.push("Geared motor: the operating points' figures are the output shaft's, the rig settings the motor shaft's.".into());
    }
    out.push("A load step counts its two settled levels only: the transient between them (inertia, friction at low speed) adds information the plan does not count.".into());
    out
}

/// `plan.md`: the operating points, the ranking, the top candidates in detail and the notes.
pub fn markdown(plan: &Plan, display: &PressureDisplay, source: &str) -> String {
    let mut s = format!("# Which measurement next: {source}\n\nOperating points: ");
    let ps: Vec<String> = plan
        .options
        .pressures_pa
        .iter()
        .map(|p| display.text(*p))
        .collect();
    s += &format!("{} {}", ps.join(", "), display.label());
    if let Some(w) = &plan.options.speeds_rad_s {
        let r: Vec<String> = w
            .iter()
            .map(|w| rounded(Unit::Rpm.from_si(*w, 0.0), 0.0))
            .collect();
        s += &format!(" at {} rpm", r.join(", "));
    }
    s += ".\n\n## Ranking\n\n";
    s += &ranking_markdown(plan, display);
    s += "\n## The best candidates\n\n";
    for (i, a) in plan.ranked.iter().take(plan.options.top).enumerate() {
        s += &detail_markdown(plan, i + 1, a, display);
    }
    s += "## Notes\n\n";
    for n in notes(plan) {
        s += &format!("- {n}\n");
    }
    s
}

fn rig_json(r: &RigSettings) -> Value {
    json!({
        "p_supply_pa": r.p_supply_pa,
        "speeds_rad_s": r.speeds_rad_s,
        "throttle_m3_s_pa": r.throttle_m3_s_pa,
        "load_nm": r.load_nm,
        "points": r.points,
        "readings": r.readings,
        "duration_s": r.duration_s,
        "records": r.records,
    })
}

/// `plan.json`: everything of the plan, SI.
pub fn json(plan: &Plan) -> Value {
    let targets: Vec<Value> = plan
        .targets
        .iter()
        .map(|t| json!({"p_supply_pa": t.p_supply_pa, "speed_rad_s": t.speed_rad_s, "figure": t.figure.name(), "value_si": t.value, "band95_before": t.band_before}))
        .collect();
    let ranked: Vec<Value> = plan
        .ranked
        .iter()
        .map(|a| {
            json!({
                "kind": a.candidate.kind.name(),
                "p_supply_pa": a.candidate.at_pa,
                "cost_h": a.candidate.cost_h,
                "sigma_si": a.candidate.sigma,
                "v_reduction": a.v_reduction,
                "v_per_hour": a.v_per_hour(),
                "d_gain_nats": a.d_gain_nats,
                "mean_shrinkage": a.mean_shrinkage(),
                "shrinkage": a.shrinkage,
                "band95_after": a.band_after,
                "sd_ln_after": a.sd_after,
                "rig": rig_json(&a.candidate.rig),
            })
        })
        .collect();
    json!({
        "format": "vanefit.plan/1",
        "parameters": plan.parameters,
        "sd_ln_before": plan.sd_before,
        "targets": targets,
        "ranked": ranked,
        "not_gaussian": plan.not_gaussian,
        "dropped": plan.dropped,
        "notes": notes(plan),
    })
}

/// Writes `plan.md` and `plan.json` into `out` (which exists); returns the files written.
pub fn write(
    plan: &Plan,
    display: &PressureDisplay,
    source: &str,
    out: &Path,
) -> Result<Vec<PathBuf>, PlanReportError> {
    let md = out.join("plan.md");
    let js = out.join("plan.json");
    let text = serde_json::to_string_pretty(&json(plan)).unwrap_or_default() + "\n";
    for (path, bytes) in [(&md, markdown(plan, display, source)), (&js, text)] {
        crate::io::write_atomic(path, bytes.as_bytes()).map_err(|source| {
            PlanReportError::Write {
                path: path.clone(),
                source,
            }
        })?;
    }
    Ok(vec![md, js])
}
