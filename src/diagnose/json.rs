//! The machine-readable outputs of a diagnosis: `diagnosis.json` (docs/formats.md,
//! "Diagnosis") and the extended model's fit file.

use super::analysis::Location;
use super::{discover, Diagnosis, ExtendedInterval, ModelKind, FORMAT};
use crate::data::fitfile::FitFile;
use crate::model::params::estimated_names as names_for;
use serde_json::{json, Value};

/// `diagnosis.json` (docs/formats.md, "Diagnosis"). Uncatalogued entries of `selected` also
/// carry `balance`, `feature`, `formula` and a `description` in words; a leak path also its
/// ends `from`, `to` and its flow `law`.
pub fn to_json(d: &Diagnosis) -> Value {
    let loc = |l: &Location| {
        json!({
            "experiment": l.kind.id(),
            "channel": l.column,
            "x_range": [l.x_range[0], l.x_range[1]],
            "severity": round(l.severity),
        })
    };
    let candidates: Vec<Value> = d
        .candidates
        .iter()
        .filter(|c| matches!(c.kind, ModelKind::Single | ModelKind::Uncatalogued))
        .filter(|c| c.label != "uncatalogued (2 terms)")
        .map(|c| {
            json!({
                "effect": c.label,
                "cost": c.fitted.cost,
                "delta_bic": round(c.delta_bic),
            })
        })
        .collect();
    let selected: Vec<Value> = d
        .selected
        .iter()
        .map(|s| {
            let params: serde_json::Map<String, Value> = s
                .parameters
                .iter()
                .map(|(n, v, _)| (n.clone(), json!(v)))
                .collect();
            let mut o = serde_json::Map::new();
            o.insert("effect".into(), json!(s.effect));
            o.insert("category".into(), json!(s.category.id()));
            o.insert("parameters".into(), Value::Object(params));
            o.insert("delta_bic".into(), json!(round(s.delta_bic)));
            if let Some(t) = &s.term {
                o.insert("balance".into(), json!(discover::balance_name(t.balance)));
                o.insert("feature".into(), json!(discover::feature_name(t)));
                o.insert("formula".into(), json!(discover::formula(t)));
                o.insert("description".into(), json!(discover::describe(t)));
                if let crate::model::motor::BalanceId::Path(path) = t.balance {
                    o.insert("from".into(), json!(path.from.id().0));
                    o.insert("to".into(), json!(path.to.id().0));
                    o.insert("law".into(), json!(discover::pressure_id(t.pressure)));
                }
            }
            Value::Object(o)
        })
        .collect();
    let mut extended =
        json!({ "cost": d.extended.fitted.cost, "noise_ratio": round(d.extended.noise_ratio) });
    if !d.extended_intervals.is_empty() {
        let intervals: Vec<Value> = d.extended_intervals.iter().map(interval).collect();
        extended["intervals"] = Value::Array(intervals);
    }
    json!({
        "format": FORMAT,
        "mismatch": d.mismatch,
        "baseline": { "cost": d.baseline.fitted.cost, "noise_ratio": round(d.baseline.noise_ratio) },
        "locations": d.locations.iter().map(loc).collect::<Vec<_>>(),
        "candidates": candidates,
        "selected": selected,
        "extended": extended,
    })
}

/// One of `extended.intervals`: the parameter (or a discovered term's `coefficient` with the
/// term's `formula`), its estimate and the 95 % interval's ends, SI (`null`: open on that
/// side), and how it was obtained.
fn interval(e: &ExtendedInterval) -> Value {
    let i = &e.interval;
    let mut o = json!({
        "parameter": i.name,
        "value": i.value,
        "lo": i.lo,
        "hi": i.hi,
        "method": i.method,
    });
    if let Some(t) = &e.term {
        o["formula"] = json!(discover::formula(t));
    }
    o
}

/// Four decimals: enough for ratios and ΔBIC, and stable in diffs.
fn round(v: f64) -> f64 {
    if v.is_finite() {
        (v * 1e4).round() / 1e4
    } else {
        v
    }
}

/// The extended model as a fit file (docs/formats.md, "Fit files", `vanefit.fit/1`).
/// Discovered terms have no catalog id, so they go in the extra list `model.discovered`
/// ([`FitFile::extra`]): readers that do not know it ignore it and then simulate without
/// the terms.
pub fn extended_fit_file(d: &Diagnosis) -> Value {
    let f = &d.extended.fitted;
    let mut file = FitFile::from_params(&d.dataset, f.params.clone(), f.effects.clone());
    file.estimated = names_for(&f.effects);
    file.cost = Some(f.cost);
    file.extra = f.extra.clone();
    file.to_json()
}
