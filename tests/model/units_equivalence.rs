//! The same data written in other units gives the same simulation and the same cost: a unit is read
//! once, at the import. `measurements/ar034-synthetic-units` is `measurements/ar034-synthetic` with
//! speed in rad/s, flows in l/min ANR and kg/s, port-1 pressure in bar gauge and the throttle in
//! dm³/(s·bar), row for row. It is written by `regenerate_units_dataset` below:
//!
//! ```text
//! cargo test --test model -- --ignored regenerate_units_dataset
//! ```
//!
//! and `shipped_units_dataset_is_up_to_date` checks the shipped copy against it.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use vanefit::data::Dataset;
use vanefit::model::EffectSet;
use vanefit::model::Motor;
use vanefit::model::MotorParams;
use vanefit::numerics::DefaultSolver;
use vanefit::objective::{CostModel, CostOptions};
use vanefit::sim::Experiment;
use vanefit::units::{column_name, Quantity, Unit};

fn measurements(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("measurements")
        .join(name)
}

const SOURCE: &str = "ar034-synthetic";
const TARGET: &str = "ar034-synthetic-units";

/// The unit each quantity is written in, per recording file.
fn target_unit(file: &str, q: Quantity) -> Unit {
    match (q, file) {
        (Quantity::Speed, _) => Unit::RadS,
        (Quantity::Flow1, _) => Unit::LMinAnr,
        (Quantity::Flow2, _) => Unit::KgS,
        (Quantity::PPort1, _) => Unit::BarG,
        (Quantity::CPort2, _) => Unit::Dm3SBar,
        (q, _) => q.si_unit(),
    }
}

/// A key that orders floats like `f64::total_cmp`, and its inverse.
fn key(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    if b < 0 {
        b ^ i64::MAX
    } else {
        b
    }
}
fn unkey(k: i64) -> f64 {
    f64::from_bits((if k < 0 { k ^ i64::MAX } else { k }) as u64)
}

/// `si` in unit `u`, chosen among the nearby floats so that reading it back gives `si`
/// bit for bit where such a value exists: a bisection on the float grid, as `to_si` is
/// monotone.
fn exact_in(u: Unit, si: f64, p_atm: f64) -> f64 {
    let guess = u.from_si(si, p_atm);
    if u.to_si(guess, p_atm) == si {
        return guess;
    }
    let back = |k: i64| u.to_si(unkey(k), p_atm);
    let (mut lo, mut hi) = (key(guess) - (1 << 24), key(guess) + (1 << 24));
    if !(back(lo) <= si && back(hi) >= si) {
        return guess;
    }
    // Smallest k with back(k) >= si.
    while hi - lo > 1 {
        let mid = lo + (hi - lo) / 2;
        if back(mid) >= si {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    if back(hi) == si {
        unkey(hi)
    } else {
        guess
    }
}

/// An SI value as text in unit `u` that reads back as exactly that SI value. For a unit
/// that is 10^k SI units the decimal exponent of the value's shortest representation is
/// shifted (the import shifts it back before rounding); otherwise the float chosen by
/// `exact_in` is written.
fn written_in(u: Unit, si: f64, p_atm: f64) -> String {
    if let Some(k) = u.decimal_exponent() {
        let text = format!("{si:e}");
        let (mantissa, exponent) = text.split_once('e').expect("LowerExp writes an exponent");
        let e: i32 = exponent.parse().expect("an integer exponent");
        return format!("{mantissa}e{}", e - k);
    }
    format!("{:e}", exact_in(u, si, p_atm))
}

/// The files of the converted dataset: name → text. Values are converted from the SI
/// values of the source and written so that they read back as the same SI value bit for
/// bit where the unit allows it (`written_in`): always for decimal units, mostly for bar
/// gauge and l/min ANR (where some SI values have no exact counterpart; the last bit
/// differs then).
fn converted_files() -> BTreeMap<String, String> {
    let src = measurements(SOURCE);
    let ds = Dataset::load(&src).unwrap();
    let mut files = BTreeMap::new();
    for ex in &ds.experiments {
        let rec = &ex.recording;
        let units: Vec<Unit> = rec
            .columns
            .iter()
            .map(|c| target_unit(&ex.file, c.quantity))
            .collect();
        let mut text = rec
            .columns
            .iter()
            .zip(&units)
            .map(|(c, u)| column_name(c.quantity, *u))
            .collect::<Vec<_>>()
            .join(",");
        text.push('\n');
        for r in 0..rec.rows() {
            let row: Vec<String> = rec
                .columns
                .iter()
                .zip(&units)
                .map(|(c, u)| {
                    if *u == c.unit {
                        c.raw[r].to_string()
                    } else {
                        written_in(*u, c.si[r], ds.p_atm_pa)
                    }
                })
                .collect();
            text.push_str(&row.join(","));
            text.push('\n');
        }
        files.insert(ex.file.clone(), text);
    }
    let rig = std::fs::read_to_string(src.join("rig.toml")).unwrap();
    let mut lines = rig.lines();
    let first = lines.next().unwrap_or_default();
    let mut out = format!(
        "# The dataset {SOURCE} written in other units (speed rad/s, flows l/min ANR and kg/s,\n\
         # port-1 pressure bar gauge, throttle dm3/(s*bar)); same rows. Written by\n\
         # tests/units_equivalence.rs (regenerate_units_dataset).\n\
         # Source: {}\n",
        first.trim_start_matches("# ")
    );
    for l in lines {
        out.push_str(l);
        out.push('\n');
    }
    files.insert("rig.toml".into(), out);
    let truth = std::fs::read_to_string(src.join("truth.json")).unwrap();
    files.insert(
        "truth.json".into(),
        truth.replace(
            &format!("\"dataset\": \"{SOURCE}\""),
            &format!("\"dataset\": \"{TARGET}\""),
        ),
    );
    files
}

#[test]
#[ignore = "writes measurements/ar034-synthetic-units; run by hand after changing the source"]
fn regenerate_units_dataset() {
    let dir = measurements(TARGET);
    std::fs::create_dir_all(&dir).unwrap();
    for (name, text) in converted_files() {
        std::fs::write(dir.join(name), text).unwrap();
    }
}

#[test]
fn shipped_units_dataset_is_up_to_date() {
    let dir = measurements(TARGET);
    for (name, text) in converted_files() {
        let shipped = std::fs::read_to_string(dir.join(&name)).unwrap();
        assert!(
            shipped == text,
            "{name} differs from what regenerate_units_dataset writes"
        );
    }
}

fn close(a: f64, b: f64, scale: f64, rel: f64) -> bool {
    (a - b).abs() <= rel * scale.abs().max(f64::MIN_POSITIVE)
}

#[test]
fn both_datasets_hold_the_same_si_data() {
    let a = Dataset::load(&measurements(SOURCE)).unwrap();
    let b = Dataset::load(&measurements(TARGET)).unwrap();
    assert_eq!(a.experiments.len(), b.experiments.len());
    for (ea, eb) in a.experiments.iter().zip(&b.experiments) {
        assert_eq!(
            (ea.kind, ea.recording.rows()),
            (eb.kind, eb.recording.rows())
        );
        for ca in &ea.recording.columns {
            let cb = eb.recording.column(ca.quantity).unwrap();
            if !matches!(ca.quantity, Quantity::Time | Quantity::Torque) {
                assert_ne!(ca.unit, cb.unit, "{} is converted", ca.name);
            }
            let scale = ca.si.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (x, y) in ca.si.iter().zip(&cb.si) {
                assert!(close(*x, *y, scale, 1e-14), "{}: {x} vs {y}", ca.name);
            }
        }
    }
}

/// Tolerances. The inputs that drive the simulations read back bit for bit: speed and
/// conductance always; port-1 pressure except 6 of 601 rows between 4.0 and 4.23 bar
/// gauge, where the gauge values' float grid is coarser than the absolute one (1 ulp off;
/// the pressure schedule's bin means absorb them). Measured: identical simulations, cost
/// 1e-15 relative apart (the last bit of some flows in l/min ANR). Bit-identical inputs
/// matter: the adaptive BDF's step sequence is not a continuous function of its inputs,
/// and one-ulp differences in the conductance once moved the throttle's outputs by 2e-7
/// of full scale.
const SIM_REL: f64 = 1e-9;
const COST_REL: f64 = 1e-9;

#[test]
fn same_simulation_and_same_cost_in_other_units() {
    let a = Dataset::load(&measurements(SOURCE)).unwrap();
    let b = Dataset::load(&measurements(TARGET)).unwrap();
    let solver = DefaultSolver::default();
    let truth = Motor::default_motor();
    for (ea, eb) in a.experiments.iter().zip(&b.experiments) {
        let sa = Experiment::new(ea, a.p_atm_pa)
            .unwrap()
            .simulate(&truth, &solver)
            .unwrap();
        let sb = Experiment::new(eb, b.p_atm_pa)
            .unwrap()
            .simulate(&truth, &solver)
            .unwrap();
        for (q, va) in &sa.outputs {
            let vb = sb.channel(*q).unwrap();
            let scale = va.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (x, y) in va.iter().zip(vb) {
                assert!(
                    close(*x, *y, scale, SIM_REL),
                    "{} {q:?}: {x} vs {y}",
                    ea.file
                );
            }
        }
    }
    let ma = CostModel::new(&a, CostOptions::default()).unwrap();
    let mb = CostModel::new(&b, CostOptions::default()).unwrap();
    assert_eq!(ma.n_points(), mb.n_points());
    for (ra, rb) in ma.references().zip(mb.references()) {
        assert_eq!(ra.quantity, rb.quantity);
        assert_eq!(ra.reference.pieces().len(), rb.reference.pieces().len());
        assert!(close(
            ra.reference.sigma(),
            rb.reference.sigma(),
            ra.reference.sigma(),
            1e-9
        ));
    }
    let other = Motor::new(
        MotorParams::default().with("c_1e", 3.0e-9).unwrap(),
        EffectSet::empty(),
    );
    for motor in [&truth, &other] {
        let ca = ma.evaluate(motor, &solver);
        let cb = mb.evaluate(motor, &solver);
        assert!(ca.failed.is_none() && cb.failed.is_none());
        assert!(
            close(ca.total, cb.total, ca.total, COST_REL),
            "{} vs {}",
            ca.total,
            cb.total
        );
        for (x, y) in ca.channels.iter().zip(&cb.channels) {
            assert_eq!((x.channel, x.n), (y.channel, y.n));
            assert!(close(x.cost, y.cost, ca.total, COST_REL), "{x:?} vs {y:?}");
        }
    }
}
