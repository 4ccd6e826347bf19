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

/// The motors and styled pages of the "Every size and page style" table
/// (`tests/predict/every_size.rs`): style, size band and seed from the environment.
fn styled_jobs() -> Vec<StyledJob> {
    use twin::sizes::SIZE_BANDS_CM3;
    use twin::styles::PageKind;
    let list = |name: &str| std::env::var(name).ok().filter(|v| !v.trim().is_empty());
    // PAIR_PAGES "style:seed[:k@bar_g[+k@bar_g…]],…" picks pages (the band is seed / 10000 − 1)
    // and the figures (k of FIGURES, at a pressure) a figure_path steers; else PAIR_STYLES
    // (default the four styles with an unmet target), PAIR_BANDS (default all) and
    // PAIR_PER_BAND (default 8) as the page table's SIZE_STYLES, SIZE_BANDS, SIZE_PAGES.
    let kind_of = |n: &str| PageKind::ALL.into_iter().find(|k| k.name() == n.trim());
    if let Some(v) = list("PAIR_PAGES") {
        return v
            .split(',')
            .map(|x| {
                let mut parts = x.split(':');
                let k = parts.next().unwrap();
                let seed: u64 = parts.next().expect("style:seed").trim().parse().unwrap();
                let steer = parts.next().map_or(Vec::new(), |t| {
                    t.split('+')
                        .map(|f| {
                            let (k, b) = f.split_once('@').expect("k@bar_g");
                            (k.trim().parse().unwrap(), b.trim().parse().unwrap())
                        })
                        .collect()
                });
                let band = seed as usize / 10_000 - 1;
                (kind_of(k).expect("a style"), band, seed, steer)
            })
            .collect();
    }
    let kinds: Vec<PageKind> = list("PAIR_STYLES")
        .unwrap_or("full,table_row,geared,no_displacement".into())
        .split(',')
        .filter_map(kind_of)
        .collect();
    let bands: Vec<usize> = list("PAIR_BANDS").map_or((0..SIZE_BANDS_CM3.len()).collect(), |v| {
        v.split(',').map(|b| b.trim().parse().unwrap()).collect()
    });
    let per: u64 = list("PAIR_PER_BAND").map_or(8, |v| v.trim().parse().unwrap());
    let mut jobs = Vec::new();
    for k in &kinds {
        for b in &bands {
            jobs.extend((0..per).map(|i| (*k, *b, 10_000 * (*b as u64 + 1) + i, Vec::new())));
        }
    }
    jobs
}

/// A page of the size table: its style, size band, seed, and the figures (k of [`FIGURES`]
/// at bar g) a [`twin::pair::figure_path`] steers.
type StyledJob = (twin::styles::PageKind, usize, u64, Vec<(usize, f64)>);

/// One styled page's path: per figure and pressure of [`BAR_G`] the spread over the path,
/// and whether the reference printer prints the widest pair at 5–7 bar g the same.
type StyledRun = (Vec<[f64; 7]>, usize, bool, f64, Vec<[(f64, f64); 7]>);

fn styled_path(
    (kind, band, seed, steer): &StyledJob,
    dir: &std::path::Path,
) -> Result<StyledRun, String> {
    let (kind, band, seed) = (*kind, *band, *seed);
    use twin::sizes::{random_motor_in_band, SIZE_BANDS_CM3};
    use twin::styles::{print_styled_page, styled_page};
    let motor = random_motor_in_band(seed, SIZE_BANDS_CM3[band], &SPREAD);
    let page = styled_page(seed, kind);
    print_styled_page(dir, &motor, &page)?;
    eprintln!(
        "{} {seed}: {:.2} cm³, z {}, ε {:.3}, n {:.3}, b {:.3}, T_c {:.3e}, d {:.3e}",
        kind.name(),
        motor.v_disp * 1e6,
        motor.z,
        motor.eps,
        motor.n_poly,
        motor.b_crit,
        motor.t_coulomb,
        motor.visc
    );
    // PAIR_WALK: the parameters walked ("all", or names of twin::pair::WALKABLE; default
    // t_coulomb); every motor of every path prints the page, so the spread is over them all.
    let walk = std::env::var("PAIR_WALK").unwrap_or("t_coulomb".into());
    let mut path = Vec::new();
    for (j, name) in twin::pair::WALKABLE.iter().enumerate() {
        if walk == "all" || walk.split(',').any(|w| w.trim() == *name) {
            let p = twin::pair::walk_path(&motor, page.gear, &page.style, dir, &[], &BAR_G, j)?;
            path.extend(p);
        }
    }
    for &target in steer {
        let p = twin::pair::figure_path(&motor, page.gear, &page.style, dir, &BAR_G, target)?;
        path.extend(p);
    }
    let tc = {
        let t: Vec<f64> = path.iter().map(|p| p.motor.t_coulomb).collect();
        t.iter().copied().fold(0.0, f64::max) / t.iter().copied().fold(f64::INFINITY, f64::min)
    };
    if path.is_empty() {
        return Err("no path: PAIR_WALK names no parameter and no figure is steered".into());
    }
    let spreads: Vec<[f64; 7]> = (0..BAR_G.len())
        .map(|p| std::array::from_fn(|k| spread(&path, p, k).0))
        .collect();
    // Per pressure and figure, the path's range relative to the page's own motor (s = 0).
    let own = path.iter().find(|pt| pt.s == 0.0).ok_or("no s = 0")?;
    let ranges: Vec<[(f64, f64); 7]> = (0..BAR_G.len())
        .map(|p| {
            std::array::from_fn(|k| {
                let (_, lo, hi) = spread(&path, p, k);
                let f =
                    |i: usize| row_values(&path[i].rows[p])[k] / row_values(&own.rows[p])[k] - 1.0;
                (f(lo), f(hi))
            })
        })
        .collect();
    let (mut best, mut pair) = (0.0, (0, 0));
    for p in 2..BAR_G.len() {
        for k in 0..7 {
            let (d, lo, hi) = spread(&path, p, k);
            if d > best {
                (best, pair) = (d, (lo, hi));
            }
        }
    }
    let same = twin::pair::verify_same_styled_page(
        &path[pair.0].motor,
        &path[pair.1].motor,
        &page,
        &dir.join("v"),
    )?;
    Ok((spreads, path.len(), same, tc, ranges))
}

/// One page's row of [`styled_page_pairs_table`], with the error its widest pair at 5–7 bar g
/// forces and the median over its 35 figures of D/(2 + D) (the half-width a band needs to
/// hold both motors of each figure's pair).
fn styled_line(label: &str, run: &StyledRun) -> (f64, f64, String) {
    let (spreads, n, same, tc, ranges) = run;
    let worst_at = |p: usize| {
        let (k, d) = spreads[p]
            .iter()
            .enumerate()
            .fold((0, 0.0f64), |a, (k, d)| if *d > a.1 { (k, *d) } else { a });
        (k, d)
    };
    let (p57, (k57, d57)) = (2..BAR_G.len())
        .map(|p| (p, worst_at(p)))
        .fold((2, (0, 0.0)), |a, b| if b.1 .1 > a.1 .1 { b } else { a });
    let per_p: Vec<String> = (2..BAR_G.len())
        .map(|p| {
            let (k, d) = worst_at(p);
            format!("{:.1} % ({})", 100.0 * forced_error(d), FIGURES[k])
        })
        .collect();
    let (k3, d3) = worst_at(0);
    // The half-width a band needs to hold both motors of a figure's pair, D/(2 + D),
    // over the page's 35 figures: its median.
    let mut all: Vec<f64> = spreads.iter().flatten().map(|d| forced_error(*d)).collect();
    all.sort_by(f64::total_cmp);
    let med = all[all.len() / 2];
    let (lo, hi) = ranges[p57][k57];
    let line = format!(
        "| {label} | {n} | {tc:.2} | {same} | {} @ {}: {:.1} % ({:+.1} to {:+.1} % of the page's motor), {:.1} % | {} | {:.1} % ({}) | {:.1} % |",
        FIGURES[k57],
        BAR_G[p57],
        100.0 * d57,
        100.0 * lo,
        100.0 * hi,
        100.0 * forced_error(d57),
        per_p.join(" / "),
        100.0 * forced_error(d3),
        FIGURES[k3],
        100.0 * med,
    );
    (forced_error(d57), med, line)
}

/// What the styled pages of the size table cannot tell at 5–7 bar g (docs/validation.md,
/// "Every size and page style"): per page, the widest same-page pair's spread and the error
/// D/(2 + D) it forces on any point predictor, per figure at 5, 6 and 7 bar g.
#[test]
#[ignore = "long: the styled pages of the size table; run with --ignored --nocapture"]
fn styled_page_pairs_table() {
    let jobs = styled_jobs();
    let tmp = tempfile::tempdir().unwrap();
    let root = std::env::var_os("PAIR_DIR").map_or(tmp.path().to_path_buf(), Into::into);
    let t0 = std::time::Instant::now();
    let results: Vec<_> = jobs
        .par_iter()
        .map(|job| {
            let (kind, seed) = (job.0, job.2);
            let dir = root.join(format!("{}-{seed}", kind.name()));
            ((kind, seed), styled_path(job, &dir))
        })
        .collect();
    println!(
        "{} pages: {:.0} s wall\n",
        jobs.len(),
        t0.elapsed().as_secs_f64()
    );
    println!("| page | path motors | T_c range × | same page (reference printer) | widest at 5–7 bar g: figure @ bar g, spread D (the path's range relative to the page's motor), forced D/(2 + D) | forced at 5 / 6 / 7 bar g (worst figure) | forced at 3 bar g | median forced, 35 figures at 3–7 bar g |\n|---|---|---|---|---|---|---|---|");
    let (mut forced_57, mut medians) = (Vec::new(), Vec::new());
    for ((kind, seed), r) in &results {
        match r {
            Ok(run) => {
                let (forced, med, line) = styled_line(&format!("{} {seed}", kind.name()), run);
                println!("{line}");
                if run.2 {
                    forced_57.push(forced);
                    medians.push(med);
                }
            }
            Err(e) => println!("| {} {seed} | failed: {e} | | | | | | |", kind.name()),
        }
    }
    forced_57.sort_by(f64::total_cmp);
    println!(
        "\npages whose same-page pair forces > 10 % at 5–7 bar g: {} of {} (verified); worst forced {:.1} %",
        forced_57.iter().filter(|f| **f > 0.1).count(),
        forced_57.len(),
        100.0 * forced_57.last().copied().unwrap_or(0.0)
    );
    medians.sort_by(f64::total_cmp);
    println!(
        "median over the pages of the median D/(2 + D) (the half-width a band needs to hold both motors of each pair): {:.1} %",
        100.0 * medians.get(medians.len() / 2).copied().unwrap_or(0.0)
    );
}

/// A geared page is read at the output shaft: its own motor prints it digit for digit
/// through the gearbox (speeds ω/G, torques η·G·T, power η·P), and not without it.
#[test]
fn a_geared_page_is_matched_at_the_output_shaft() {
    use twin::sizes::{random_motor_in_band, SIZE_BANDS_CM3};
    use twin::styles::{print_styled_page, styled_page, PageKind};
    let tmp = tempfile::tempdir().unwrap();
    let seed = 30_007;
    let motor = random_motor_in_band(seed, SIZE_BANDS_CM3[2], &SPREAD);
    let page = styled_page(seed, PageKind::Geared);
    print_styled_page(tmp.path(), &motor, &page).unwrap();
    let r = |gear| twin::pair::page_residual(&motor, gear, &page.style, tmp.path()).unwrap();
    let (geared, plain) = (r(page.gear), r(None));
    // Within its rounding interval: ≤ 1/0.9, the figures at max power being held to 0.9 of
    // theirs (twin::pair's AT_MAX_POWER_SHARE).
    assert!(geared < 1.0 / 0.9, "through the gearbox: {geared}");
    assert!(plain > 10.0, "at the motor's shaft: {plain}");
}

/// A table row (free speed, max power with its speed and torque, air at max power; no
/// stall torque, curves or displacement) is printed digit for digit by two motors of the
/// twin's population whose stall torque at 5 bar g differs by more than 22.2 %: any point
/// prediction made from that row is off by more than 10 % at 5 bar g on one of them
/// (docs/validation.md, "Why the unmet targets are unmet").
#[test]
fn a_table_row_is_printed_alike_by_motors_that_differ_at_5_bar_g() {
    use twin::sizes::{random_motor_in_band, SIZE_BANDS_CM3};
    use twin::styles::{print_styled_page, styled_page, PageKind};
    let tmp = tempfile::tempdir().unwrap();
    let seed = 10_000;
    let motor = random_motor_in_band(seed, SIZE_BANDS_CM3[0], &SPREAD);
    let page = styled_page(seed, PageKind::TableRow);
    print_styled_page(tmp.path(), &motor, &page).unwrap();
    // Walk the inlet-side leak c_1e (index 3 of WALKABLE), the rest re-solved.
    assert_eq!(twin::pair::WALKABLE[3], "c_1e");
    let path =
        twin::pair::walk_path(&motor, None, &page.style, tmp.path(), &[], &BAR_G, 3).unwrap();
    let k_stall = FIGURES.iter().position(|f| *f == "stall_torque").unwrap();
    let (d, lo, hi) = spread(&path, 2, k_stall);
    println!(
        "stall torque at 5 bar g: spread {:.1} %, forced error {:.1} %",
        100.0 * d,
        100.0 * forced_error(d)
    );
    assert!(d > 0.2 / 0.9, "spread {d}");
    assert!(twin::pair::verify_same_styled_page(
        &path[lo].motor,
        &path[hi].motor,
        &page,
        &tmp.path().join("v")
    )
    .unwrap());
}
