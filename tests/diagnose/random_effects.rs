//! The diagnosis against effects drawn at random from the literature's leakage and friction
//! laws ([`crate::twin::laws::draw`]: law, path, size), most of them not in vanefit's
//! catalogue or term library, recorded by the independent twin generator. Each answer is
//! classed: exact (one part, at the right place: the drawn leak's path, or a torque loss for
//! a friction law), with a part that is not there (a catalog effect or term elsewhere), or
//! nothing found.
//!
//! The table (`target/random-effects.md`, ≥ 30 draws) is `#[ignore]`d:
//!
//! ```sh
//! cargo test --release --test diagnose -- --ignored --nocapture random_effect_table
//! ```

use crate::twin;
use crate::twin::laws::{Drawn, LeakLaw, Node};
use std::time::Instant;
use vanefit::diagnose::{diagnose, discover, summary, DiagnoseOptions, Diagnosis};
use vanefit::model::Category;
use vanefit::model::{BalanceId, Chamber, LeakPath, PressureFactor};

/// How an answer compares with the drawn truth.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Class {
    /// One part, at the right place.
    Exact,
    /// At least one part that is not there.
    ExtraPart,
    /// The right place, but in more than one part (none wrong).
    Split,
    /// Nothing selected.
    Missed,
}

fn chamber(n: Node) -> Chamber {
    match n {
        Node::V1 => Chamber::V1,
        Node::V2 => Chamber::V2,
        Node::Ve => Chamber::Ve,
        Node::Atm => Chamber::Atm,
    }
}

/// vanefit's nearest law of a drawn leak law.
fn nearest_law(l: LeakLaw) -> &'static [PressureFactor] {
    match l {
        LeakLaw::Laminar => &[PressureFactor::Laminar],
        LeakLaw::Quadratic => &[PressureFactor::Quadratic],
        LeakLaw::GasOrifice => &[PressureFactor::Orifice],
        LeakLaw::SaintVenant | LeakLaw::Iso6358 { .. } => &[PressureFactor::Iso6358],
        LeakLaw::CompressibleLaminar => &[PressureFactor::CompressibleLaminar],
        LeakLaw::Turbulent => &[PressureFactor::Turbulent],
    }
}

/// Whether a selected part sits where the drawn effect is: on the drawn leak's path (either
/// direction) or, for a friction law, a torque loss.
fn at_the_right_place(truth: &Drawn, s: &vanefit::diagnose::Selected) -> bool {
    match truth {
        Drawn::Leak(l) => {
            let (a, b) = (chamber(l.from), chamber(l.to));
            s.term.is_some_and(|t| {
                t.balance == BalanceId::Path(LeakPath::new(a, b))
                    || t.balance == BalanceId::Path(LeakPath::new(b, a))
            })
        }
        Drawn::Friction(_) => s.category == Category::TorqueLoss,
    }
}

/// The class of a diagnosis of `truth`, and whether a leak's law is the nearest one
/// vanefit has.
pub(crate) fn classify(truth: &Drawn, d: &Diagnosis) -> (Class, bool) {
    let right = d
        .selected
        .iter()
        .filter(|s| at_the_right_place(truth, s))
        .count();
    let class = match (d.selected.len(), right) {
        (0, _) => Class::Missed,
        (n, r) if r < n => Class::ExtraPart,
        (1, 1) => Class::Exact,
        _ => Class::Split,
    };
    let law = match truth {
        Drawn::Leak(l) => d
            .selected
            .iter()
            .filter_map(|s| s.term)
            .any(|t| nearest_law(l.law).contains(&t.pressure)),
        Drawn::Friction(_) => class == Class::Exact,
    };
    (class, law)
}

/// The effect drawn from `seed`, the twin's perturbed motor of `seed` with it and the rig
/// it is recorded on (20 Hz, rig noise), all at the size `DIAG_SIZES` gives the seed
/// ([`crate::support::table_size_cm3`]; unset: the 3.8 cm³ reference motor).
fn random_motor(seed: u64) -> (Drawn, twin::TwinMotor, twin::RecordConfig) {
    let drawn = twin::laws::draw(seed);
    let size = crate::support::table_size_cm3(seed);
    let (motor, cfg) = crate::support::sized(
        twin::perturbed_motor(1000 + seed),
        crate::twin_data::twin_rig_config(),
        size,
    );
    let drawn = size.map_or(drawn, |v| drawn.scaled(v * 1e-6 / 3.8e-6));
    let motor = twin::TwinMotor {
        laws: vec![drawn],
        ..motor
    };
    (drawn, motor, cfg)
}

/// A random case: the twin's perturbed motor of `seed` with the effect drawn from `seed`,
/// recorded as a rig does (20 Hz, rig noise).
pub(crate) fn random_case(seed: u64) -> (Drawn, vanefit::data::Dataset) {
    let (drawn, motor, cfg) = random_motor(seed);
    let ds = crate::twin_data::twin_dataset(&motor, &cfg, seed);
    (drawn, ds)
}

/// Diagnoses one random case: (class, law right, table row).
pub(crate) fn random_row(seed: u64, opts: &DiagnoseOptions) -> (Class, bool, String) {
    let (drawn, ds) = random_case(seed);
    let t0 = Instant::now();
    let d = diagnose(&ds, opts).unwrap();
    let wall_s = t0.elapsed().as_secs_f64();
    let (class, law) = classify(&drawn, &d);
    let found: Vec<String> = d
        .selected
        .iter()
        .map(|s| match &s.term {
            Some(t) => format!("{} [{}]", discover::formula(t), s.category.id()),
            None => s.effect.clone(),
        })
        .collect();
    let (before, after) = d.noise_ratios();
    let v_cm3 = crate::support::table_size_cm3(seed).unwrap_or(3.8);
    let row = format!(
        "| {seed} | {v_cm3:.2} | {} | {} | {:.0} | {before:.2} → {after:.2} | {class:?} | {} | {} | {wall_s:.0} |\n",
        drawn.describe(),
        if found.is_empty() {
            "-".to_string()
        } else {
            found.join(" + ")
        },
        d.delta_bic(),
        if law { "yes" } else { "no" },
        crate::support::evaluations(&d),
    );
    eprint!("{row}");
    eprintln!("  {}", summary(&d));
    (class, law, row)
}

/// The table header.
const HEADER: &str = "| seed | V_disp cm³ | drawn | selected | ΔBIC | noise ratio | class | law | evaluations | wall s |\n|---|---|---|---|---|---|---|---|---|---|\n";

/// The random-effect table over `RANDOM_CASES` draws (default 30, seeds 1..), the command
/// line's default options (`DIAG_EFFORT=quick` for the quick ones), on motors of the size
/// `DIAG_SIZES` says (e.g. `1-150`: drawn per seed; unset: 3.8 cm³); writes
/// `target/random-effects.md` (or `RANDOM_OUT_MD`) with the rates.
#[test]
#[ignore]
fn random_effect_table() {
    let n: u64 = std::env::var("RANDOM_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(30);
    let first: u64 = std::env::var("RANDOM_FIRST")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1);
    let (opts, opts_name) = crate::support::table_options();
    let sizes = std::env::var("DIAG_SIZES").unwrap_or("3.8".into());
    let mut md = format!("Options: {opts_name}; motor sizes {sizes} cm³.\n\n{HEADER}");
    let mut counts = [0usize; 4];
    let mut laws = 0;
    let path = std::env::var_os("RANDOM_OUT_MD").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/random-effects.md"),
        std::path::PathBuf::from,
    );
    for seed in first..first + n {
        let (class, law, row) = random_row(seed, &opts);
        counts[class as usize] += 1;
        laws += usize::from(law);
        md += &row;
        std::fs::write(&path, &md).unwrap();
    }
    let total = n as f64;
    md += &format!(
        "\nexact {} of {n} ({:.0} %), with a part that is not there {} ({:.0} %), split {}, \
         missed {}; nearest law named {laws}\n",
        counts[0],
        100.0 * counts[0] as f64 / total,
        counts[1],
        100.0 * counts[1] as f64 / total,
        counts[2],
        counts[3],
    );
    std::fs::write(&path, &md).unwrap();
    println!("{md}");
}

/// Two drawn effects in the normal run (a leak not in the library, a friction law): the
/// answer never holds a part that is not there.
#[test]
fn random_effects_short() {
    for seed in [1, 2] {
        let (class, _, row) = random_row(seed, &DiagnoseOptions::quick(1));
        assert_ne!(class, Class::ExtraPart, "{row}");
    }
}

/// The draws of the table, listed (no diagnosis).
#[test]
#[ignore]
fn random_effect_draws() {
    for seed in 1..=40 {
        println!("{seed}: {}", twin::laws::draw(seed).describe());
    }
}

/// Writes the random cases `RANDOM_SEEDS` (comma-separated, default 6,7,10) as rig folders
/// under `RANDOM_OUT` (default `target/random-cases`), for timing `vanefit diagnose` on
/// them:
///
/// ```sh
/// RANDOM_SEEDS=6,7,10 cargo test --release --test diagnose -- --ignored random_cases_to_disk
/// ```
#[test]
#[ignore]
fn random_cases_to_disk() {
    let seeds: Vec<u64> = std::env::var("RANDOM_SEEDS")
        .unwrap_or_else(|_| "6,7,10".into())
        .split(',')
        .map(|s| s.trim().parse().unwrap())
        .collect();
    let out = std::env::var("RANDOM_OUT").map_or_else(
        |_| std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("target/random-cases"),
        std::path::PathBuf::from,
    );
    for seed in seeds {
        let (drawn, motor, cfg) = random_motor(seed);
        let path = out.join(format!("random-{seed}"));
        twin::write_dataset(&path, &motor, &cfg, seed).unwrap();
        println!("{}: {}", path.display(), drawn.describe());
    }
}

/// Draw 10, load-dependent Coulomb friction μ·|T_air|·sign(ω) (the twin's own air torque),
/// with the command line's default options: one part, the library's load-dependent law on
/// vanefit's air torque (not a catalog pressure-dependent friction plus a second Coulomb
/// term), with a positive fraction of the air torque near the drawn μ (a loss, never a
/// gain).
#[test]
fn load_dependent_coulomb_is_one_law() {
    let (drawn, ds) = random_case(10);
    let twin::laws::Drawn::Friction(twin::laws::FrictionLaw::LoadDependent { mu }) = drawn else {
        panic!("draw 10 changed: {}", drawn.describe());
    };
    let d = diagnose(&ds, &DiagnoseOptions::full(4, 1)).unwrap();
    let (class, _) = classify(&drawn, &d);
    assert_eq!(class, Class::Exact, "{}", summary(&d));
    let t = d.selected[0]
        .term
        .expect("a library term, not a catalog effect");
    assert_eq!(
        (t.balance, t.pressure),
        (BalanceId::Torque, PressureFactor::AirTorque),
        "{}",
        summary(&d)
    );
    // The two implementations' air torques differ in their details (cycle, blend), so the
    // fraction agrees with μ to a few per cent, not exactly.
    assert!(
        t.coefficient > 0.0 && (t.coefficient / mu - 1.0).abs() < 0.15,
        "k = {} for μ = {mu}",
        t.coefficient
    );
}
