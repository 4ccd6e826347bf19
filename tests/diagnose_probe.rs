mod diagnose_support;
use vanefit::diagnose::{diagnose, summary, DiagnoseOptions};
use vanefit::effects::EffectSet;
use vanefit::motor::Motor;

#[test]
#[ignore]
fn probe() {
    let effects = std::env::var("FX").unwrap_or_default();
    let set = EffectSet::parse_list(&effects).unwrap();
    let mut p = diagnose_support::perturbed_base();
    if let Ok(v) = std::env::var("PV") {
        for kv in v.split(',') {
            let (k, v) = kv.split_once('=').unwrap();
            p = p.with(k, v.parse().unwrap()).unwrap();
        }
    }
    let truth = Motor::new(p, set);
    let ds = diagnose_support::dataset("probe", diagnose_support::synthesize(&truth, 11));
    let mut o = if std::env::var("FULL").is_ok() { DiagnoseOptions::full(4, 1) } else { DiagnoseOptions::quick(1) };
    o.progress = std::env::var("PROGRESS").is_ok();
    let d = diagnose(&ds, &o).unwrap();
    eprintln!("{}", summary(&d));
    let c = d.concealment.as_ref().unwrap();
    eprintln!("RESULT fx={effects} {:?} alone={:?} joint={:?} LRp={:.1e} sel={:?} dbic={:.1} ratio {:.3}->{:.3} wall {:.1}",
        std::env::var("PV").unwrap_or_default(),
        c.experiments.iter().map(|e| ((e.alone_ratio * 1000.0).round() / 1000.0, (e.alone_limit * 1000.0).round() / 1000.0)).collect::<Vec<_>>(),
        c.experiments.iter().map(|e| (e.joint_ratio * 1000.0).round() / 1000.0).collect::<Vec<_>>(),
        c.p_value,
        d.selected.iter().map(|s| (s.effect.clone(), s.parameters.iter().map(|p| (p.0.clone(), p.1)).collect::<Vec<_>>())).collect::<Vec<_>>(),
        d.delta_bic(), d.baseline.noise_ratio, d.extended.noise_ratio, d.wall_s);
    for c in &d.candidates { eprintln!("   {:<45} {:>9.1} {:.3}", c.label, c.delta_bic, c.noise_ratio); }
    vanefit::diagnose::write(&d, std::path::Path::new("/tmp/diag_probe")).unwrap();
}
