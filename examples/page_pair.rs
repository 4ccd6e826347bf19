//! Probe: two twin motors that print the same catalogue page (docs/validation.md, "What a
//! page cannot tell").
//!
//! `cargo run --release --example page_pair -- SEED [EXTRA [DIR]]`
//!
//! Prints the twin's page of random motor SEED (tests/twin/page.rs) into DIR (default a
//! folder in the system's temporary directory), walks its Coulomb friction away from the
//! truth while every other parameter the page does not print is re-solved to keep the page
//! (tests/twin/pair.rs), and prints, per motor of that path, T_c, d and the figures at 3 and
//! 7 bar g; then the widest pair at 3 bar g, the least worst error it forces on any point
//! prediction (D/(2 + D)), and whether the twin's reference printer prints both pages byte
//! for byte the same. EXTRA adds figures at other pressures to the page, "k@bar_g"
//! comma-separated with k in the order free speed, max power, speed, torque at max power,
//! stall torque, air at max power, air at free speed (e.g. "0@4,1@4": a second pressure).

use twin::page::{page_style, print_page, random_motor, row_values, FIGURES, SPREAD};
use twin::pair::{forced_error, friction_path, spread, verify_same_page};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let Some(seed) = args.get(1).and_then(|s| s.parse::<u64>().ok()) else {
        eprintln!("usage: page_pair SEED [EXTRA [DIR]]   (EXTRA e.g. \"0@4,1@4\")");
        std::process::exit(2);
    };
    let mut extra = Vec::new();
    for x in args.get(2).map_or("", String::as_str).split(',') {
        if x.trim().is_empty() {
            continue;
        }
        let (k, b) = x.split_once('@').ok_or("EXTRA: k@bar_g")?;
        extra.push((k.trim().parse::<usize>()?, b.trim().parse::<f64>()?));
    }
    let dir = args.get(3).map_or_else(
        || std::env::temp_dir().join(format!("vanefit-page-pair-{seed}")),
        std::path::PathBuf::from,
    );
    std::fs::create_dir_all(&dir)?;
    let motor = random_motor(seed, &SPREAD);
    let style = page_style(seed);
    print_page(&dir, &motor, &style)?;
    let path = friction_path(&motor, &style, &dir, &extra, &[3.0, 7.0])?;
    println!(
        "motor {seed}: {:.2} cm³, page at {}, extra figures {extra:?}; {} motors print its page",
        motor.v_disp * 1e6,
        style.supply.0,
        path.len()
    );
    println!("T_c N·m, d N·m·s/rad, worst printed residual, then at 3 and 7 bar g: free speed rad/s, max power W, stall torque N·m");
    for pt in &path {
        let (a, b) = (row_values(&pt.rows[0]), row_values(&pt.rows[1]));
        println!(
            "{:.5} {:.3e} {:.2} | {:.1} {:.3} {:.4} | {:.1} {:.3} {:.4}",
            pt.motor.t_coulomb,
            pt.motor.visc,
            pt.worst_residual,
            a[0],
            a[1],
            a[4],
            b[0],
            b[1],
            b[4]
        );
    }
    let (mut d, mut k, mut lo, mut hi) = (0.0, 0, 0, 0);
    for kk in 0..FIGURES.len() {
        let (dd, l, h) = spread(&path, 0, kk);
        if dd > d {
            (d, k, lo, hi) = (dd, kk, l, h);
        }
    }
    let same = verify_same_page(&path[lo].motor, &path[hi].motor, &style, &dir.join("pair"))?;
    println!(
        "widest at 3 bar g: {} {:.4e} and {:.4e} (SI), spread {:.1} %, forced error {:.1} %; same page byte for byte: {same}",
        FIGURES[k],
        row_values(&path[lo].rows[0])[k],
        row_values(&path[hi].rows[0])[k],
        100.0 * d,
        100.0 * forced_error(d)
    );
    println!(
        "the two motors:\n{:?}\n{:?}",
        path[lo].motor, path[hi].motor
    );
    Ok(())
}
