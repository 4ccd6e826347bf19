//! What a catalogue page printed at one supply pressure cannot tell, shown with the twin
//! alone (no vanefit code): for a random motor's page, other motors of the twin's population
//! that print the very same page (every figure and curve cell, byte for byte) but whose
//! figures at 3–7 bar g differ ([`twin::pair`]: the Coulomb friction moved, every other
//! parameter the page does not print re-solved to keep the page).
//!
//! If two motors print the same page and a figure differs by D between them, any point
//! prediction made from the page errs by at least D/(2 + D) on one of them (≥ 10 % from
//! D ≥ 22.2 %), whatever the method. The long table runs 60 motors; the CI version one.

use crate::twin;

use rayon::prelude::*;
use twin::catalogue::catalogue_row;
use twin::experiment::Conditions;
use twin::motor::P_ATM_PA;
use twin::page::{page_style, print_page, random_motor, row_values, FIGURES, SPREAD};
use twin::pair::{forced_error, friction_path, spread, verify_same_page, PathPoint};

/// Pressures of the figures compared, bar g.
const BAR_G: [f64; 5] = [3.0, 4.0, 5.0, 6.0, 7.0];

/// A motor's page and the path of motors printing it.
fn path_of(
    seed: u64,
    dir: &std::path::Path,
    extra: &[(usize, f64)],
) -> Result<(twin::page::PageStyle, Vec<PathPoint>), String> {
    let motor = random_motor(seed, &SPREAD);
    let style = page_style(seed);
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    print_page(dir, &motor, &style)?;
    let path = friction_path(&motor, &style, dir, extra, &BAR_G)?;
    Ok((style, path))
}

/// The largest spread over the figures at pressure index `p` (or all pressures with
/// `None`): (spread, figure, pressure index, lo, hi).
fn widest(path: &[PathPoint], p: Option<usize>) -> (f64, usize, usize, usize, usize) {
    let ps: Vec<usize> = p.map_or((0..BAR_G.len()).collect(), |p| vec![p]);
    let mut best = (0.0, 0, 0, 0, 0);
    for &p in &ps {
        for k in 0..FIGURES.len() {
            let (d, lo, hi) = spread(path, p, k);
            if d > best.0 {
                best = (d, k, p, lo, hi);
            }
        }
    }
    best
}

#[test]
fn a_second_motor_prints_the_same_page_and_differs_at_3_bar_g() {
    // Motor 32 (3.1 cm³, page at 5 bar g): the worst of the 60-motor page table (vanefit's max
    // power at 3 bar g +41 %).
    let tmp = tempfile::tempdir().unwrap();
    let (style, path) = path_of(32, tmp.path(), &[]).unwrap();
    // The fast solver of the pair search agrees with the twin's reference rows.
    let m = random_motor(32, &SPREAD);
    let c = Conditions {
        p_supply_pa: P_ATM_PA + 3e5,
        ..Conditions::default()
    };
    let reference = row_values(&catalogue_row(&m, &c).unwrap());
    let fast = row_values(&twin::pair::fast_row(&m, 3.0, 500.0).unwrap());
    for k in 0..7 {
        assert!(
            (fast[k] / reference[k] - 1.0).abs() < 1e-6,
            "{}: fast {} reference {}",
            FIGURES[k],
            fast[k],
            reference[k]
        );
    }
    assert!(path.iter().any(|pt| pt.s == 0.0 && pt.motor == m));
    for pt in &path {
        assert!(pt.worst_residual < 1.0, "{pt:?}");
        assert!(twin::pair::population_distance(&pt.motor) <= twin::pair::Z_MAX);
    }
    // Max power at 3 bar g differs by more than 50 % between two motors of the path (a
    // forced error above 20 %; measured 98.8 %), and the twin's reference printer prints
    // the same two files for both.
    let (d, lo, hi) = spread(&path, 0, 1);
    println!(
        "max power at 3 bar g: {:.2} W and {:.2} W (T_c {:.4} and {:.4} N·m), spread {:.1} %, forced error {:.1} %",
        path[lo].rows[0].max_power_w,
        path[hi].rows[0].max_power_w,
        path[lo].motor.t_coulomb,
        path[hi].motor.t_coulomb,
        100.0 * d,
        100.0 * forced_error(d)
    );
    assert!(d > 0.5, "spread {d}");
    assert!(verify_same_page(
        &path[lo].motor,
        &path[hi].motor,
        &style,
        &tmp.path().join("v")
    )
    .unwrap());
    // A second pressure on the page, its free speed and max power at 4 bar g (3 digits),
    // removes it: no figure at 3–7 bar g then spreads by 10 % along the path.
    let (_, path) = path_of(32, &tmp.path().join("extra"), &[(0, 4.0), (1, 4.0)]).unwrap();
    let (d, k, p, ..) = widest(&path, None);
    println!(
        "with the free speed and max power at 4 bar g: widest spread {:.1} % ({} at {} bar g)",
        100.0 * d,
        FIGURES[k],
        BAR_G[p]
    );
    assert!(d < 0.1, "{} at {} bar g spreads {d}", FIGURES[k], BAR_G[p]);
}

/// A motor's page style, its path and whether the reference printer prints the widest
/// pair's pages the same.
type PairRun = (twin::page::PageStyle, Vec<PathPoint>, bool);

/// Per figure k and pressure p, over the motors: the forced errors and the errors of the
/// set-centre predictor 2·f_lo·f_hi/(f_lo + f_hi) on the page's own motor.
struct Cells {
    forced: Vec<Vec<Vec<f64>>>,
    centre: Vec<Vec<Vec<f64>>>,
}

fn summary(label: &str, values: &[f64]) -> String {
    let mut v: Vec<f64> = values.iter().map(|x| x.abs()).collect();
    v.sort_by(f64::total_cmp);
    let over = v.iter().filter(|x| **x > 0.1).count();
    format!(
        "| {label} | {:.1} % | {} / {} | {:.1} % |",
        100.0 * v.last().copied().unwrap_or(0.0),
        over,
        v.len(),
        100.0 * v.get(v.len() / 2).copied().unwrap_or(0.0)
    )
}

#[test]
#[ignore = "long: 60 motors; run with --ignored --nocapture (PAIR_EXTRA=\"0@4,1@4\" adds the free speed and max power at 4 bar g to every page)"]
fn page_pairs_table_over_random_motors() {
    // PAIR_EXTRA: figures added to each page, "k@bar_g" comma-separated (k in FIGURES order).
    let extra: Vec<(usize, f64)> = std::env::var("PAIR_EXTRA").map_or(Vec::new(), |v| {
        v.split(',')
            .filter(|x| !x.trim().is_empty())
            .map(|x| {
                let (k, b) = x.split_once('@').unwrap();
                (k.trim().parse().unwrap(), b.trim().parse().unwrap())
            })
            .collect()
    });
    // PAGE_MOTORS (default 60) or PAGE_SEEDS (comma-separated) pick the motors; PAIR_DIR
    // keeps the pages (else a temporary folder).
    let n: u64 = std::env::var("PAGE_MOTORS").map_or(60, |v| v.parse().unwrap());
    let seeds: Vec<u64> = std::env::var("PAGE_SEEDS").map_or((0..n).collect(), |v| {
        v.split(',').map(|s| s.trim().parse().unwrap()).collect()
    });
    let n = seeds.len() as u64;
    let tmp = tempfile::tempdir().unwrap();
    let root = std::env::var_os("PAIR_DIR").map_or(tmp.path().to_path_buf(), Into::into);
    let t0 = std::time::Instant::now();
    let results: Vec<(u64, Result<PairRun, String>)> = seeds
        .into_par_iter()
        .map(|seed| {
            let dir = root.join(format!("m{seed}"));
            let r = path_of(seed, &dir, &extra).and_then(|(style, path)| {
                let (_, _, _, lo, hi) = widest(&path, None);
                // Pages with an extra figure: the byte check covers the printed page only.
                let same =
                    verify_same_page(&path[lo].motor, &path[hi].motor, &style, &dir.join("v"))?;
                Ok((style, path, same))
            });
            (seed, r)
        })
        .collect();
    println!(
        "{n} motors, extra figures {extra:?}: {:.0} s wall",
        t0.elapsed().as_secs_f64()
    );
    let mut cells = Cells {
        forced: vec![vec![Vec::new(); BAR_G.len()]; 7],
        centre: vec![vec![Vec::new(); BAR_G.len()]; 7],
    };
    let (mut over_20, mut over_222, mut over_222_at3, mut verified, mut ok) = (0, 0, 0, 0, 0);
    println!("seed, V_disp cm³, supply, path motors, T_c range ×, widest at 3 bar g (figure: spread, forced error), widest at 3–7 bar g (figure @ bar: spread, forced error), same page byte for byte, largest population distance");
    for (seed, r) in &results {
        let (style, path, same) = match r {
            Ok(x) => x,
            Err(e) => {
                println!("{seed}: failed: {e}");
                continue;
            }
        };
        ok += 1;
        let m = &path.iter().find(|pt| pt.s == 0.0).unwrap().motor;
        let truth_i = path.iter().position(|pt| pt.s == 0.0).unwrap();
        for k in 0..7 {
            for p in 0..BAR_G.len() {
                let (d, lo, hi) = spread(path, p, k);
                cells.forced[k][p].push(forced_error(d));
                let (a, b) = (
                    row_values(&path[lo].rows[p])[k],
                    row_values(&path[hi].rows[p])[k],
                );
                let centre = 2.0 * a * b / (a + b);
                cells.centre[k][p].push(centre / row_values(&path[truth_i].rows[p])[k] - 1.0);
            }
        }
        let (d3, k3, ..) = widest(path, Some(0));
        let (d, k, p, ..) = widest(path, None);
        // A pair counts only where the reference printer prints both pages the same.
        over_20 += usize::from(d > 0.2 && *same);
        over_222 += usize::from(d > 0.2 / 0.9 && *same);
        over_222_at3 += usize::from(d3 > 0.2 / 0.9 && *same);
        verified += usize::from(*same);
        let dist = path
            .iter()
            .map(|pt| twin::pair::population_distance(&pt.motor))
            .fold(0.0, f64::max);
        println!(
            "{seed} {:.2} {:?} {} {:.2}–{:.2} {}: {:.1} % {:.1} %; {} @ {}: {:.1} % {:.1} %; {same} {dist:.2}",
            m.v_disp * 1e6,
            style.supply.0,
            path.len(),
            path[0].s.exp(),
            path[path.len() - 1].s.exp(),
            FIGURES[k3],
            100.0 * d3,
            100.0 * forced_error(d3),
            FIGURES[k],
            BAR_G[p],
            100.0 * d,
            100.0 * forced_error(d)
        );
    }
    println!(
        "\n{ok} motors: a same-page pair with a spread > 20 % at 3–7 bar g: {over_20}; > 22.2 % (forces a worst error ≥ 10 %): {over_222} (at 3 bar g: {over_222_at3}); pairs printed byte for byte the same by the reference printer: {verified}\n"
    );
    println!("forced worst error (D/(2 + D) of the widest same-page pair) and the error of the set-centre predictor 2·f_lo·f_hi/(f_lo + f_hi) on the page's own motor\n");
    println!("| | forced: worst | forced > 10 % | forced: median | centre: worst |error| | centre > 10 % | centre: median |error| |\n|---|---|---|---|---|---|---|");
    let row = |label: &str, f: Vec<f64>, c: Vec<f64>| {
        let a = summary(label, &f);
        let b = summary("", &c);
        println!("{a}{}", &b[4..]);
    };
    let all = |v: &Vec<Vec<Vec<f64>>>, kf: &dyn Fn(usize, usize) -> bool| -> Vec<f64> {
        let mut out = Vec::new();
        for (k, per_pressure) in v.iter().enumerate() {
            for (p, values) in per_pressure.iter().enumerate() {
                if kf(k, p) {
                    out.extend(values);
                }
            }
        }
        out
    };
    row(
        "all",
        all(&cells.forced, &|_, _| true),
        all(&cells.centre, &|_, _| true),
    );
    for (k, name) in FIGURES.iter().enumerate() {
        row(
            name,
            all(&cells.forced, &|kk, _| kk == k),
            all(&cells.centre, &|kk, _| kk == k),
        );
    }
    for (p, bar) in BAR_G.iter().enumerate() {
        row(
            &format!("{bar} bar g"),
            all(&cells.forced, &|_, pp| pp == p),
            all(&cells.centre, &|_, pp| pp == p),
        );
    }
    let failed = results.iter().filter(|(_, r)| r.is_err()).count();
    assert!(failed * 10 <= n as usize, "{failed} of {n} motors failed");
}
