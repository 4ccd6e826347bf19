//! Probe: a fit's posterior as the delta method takes it against the one the ensemble
//! sampler draws (docs/validation.md, "Sampled bands on a page").
//!
//! `cargo run --release --example page_posterior -- FIT.json DATASET_DIR [STEPS [BURN_IN [OTHER_FIT.json]]]`
//!
//! Prints, per estimated parameter, σ of ln θ from the fit's profile interval (what the
//! delta method uses), from the fit file's curvature covariance and from the samples; then
//! the correlations of the delta method's C = S·R·S, of the curvature and of the samples,
//! and the eigenvalues of the three covariances (the directions the data pin). Before that,
//! how far the posterior is from its Laplace approximation: importance sampling from the
//! sampler's t proposal (4000 draws), its effective sample size (Σw)²/Σw² and the Hill
//! estimate of the weights' Pareto tail index k̂ over the largest 20 % (k̂ > 0.7: the
//! proposal is no use as an importance density, Vehtari et al. 2024, "Pareto smoothed
//! importance sampling", JMLR 25). `SAMPLER=chains` samples with `estimate::run_chains`
//! (8 chains) instead of the ensemble; then each chain's mean of the parameter with the
//! largest R̂ shows whether chains sit in different places. `SAMPLER=map`: the transport
//! sampler's parts by hand (a pilot ensemble of `PILOT` steps, `MAPS` quadratic maps, 8
//! chains in the map's coordinates; `SCALE10` the t's scale × 10, `MAPENS=1` the ensemble
//! in those coordinates instead), with the mapped t's k̂ per round. `HESS=step`: the Laplace
//! approximation from the full Hessian of ln p at that step, and its k̂. `DIAG=1`: why the
//! posterior is not Gaussian (`diagnose`), then stop.

use nalgebra::DMatrix;
use std::path::Path;
use vanefit::estimate::{gaussian_of, ImportanceCheck, LogDensity, LogPrior, Mapped, QuadraticMap};
use vanefit::estimate::{
    run_chains, run_ensemble_with, summarise, ChainSettings, Chains, EnsembleSettings,
    FitLikelihood, FitPosterior, Moves, TProposal,
};
use vanefit::predict::ParamUncertainty;
use vanefit::prelude::*;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: page_posterior FIT.json DATASET_DIR [STEPS [BURN_IN [OTHER_FIT.json]]]");
        std::process::exit(2);
    }
    let steps: usize = args.get(3).map_or(Ok(4000), |s| s.parse())?;
    let burn_in: usize = args.get(4).map_or(Ok(1000), |s| s.parse())?;
    let fit = FitFile::read(Path::new(&args[1]))?;
    let ds = Dataset::load(Path::new(&args[2]))?;
    let like = FitLikelihood::from_fit(&ds, &fit)?;
    let prior = |v: &[f64]| like.log_prior(v);
    let post = FitPosterior::new(&like).with_prior(&prior as &dyn LogPrior);
    let names = like.names();
    let d = names.len();
    let walkers = (4 * d).max(16).div_ceil(2) * 2;
    let centre = post.to_coords(&like.estimate());
    let unc = ParamUncertainty::of(&fit, None);
    // Starts: a small ball about the estimate, as predict's.
    let mut seed = 12345u64;
    let mut uniform = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    };
    // START=laplace: starts drawn from N(x̂, Σ), Σ the fit file's curvature covariance in
    // the sampler's coordinates; else a ball of ±0.5 % about the estimate.
    let laplace = std::env::var("START").is_ok_and(|v| v == "laplace");
    let chol = fit.covariance.as_ref().and_then(|c| {
        let est = like.estimate();
        let log = like.log_scale();
        let idx: Vec<usize> = names
            .iter()
            .map(|n| c.parameters.iter().position(|m| m == n))
            .collect::<Option<_>>()?;
        let jac = |i: usize| if log[i] { 1.0 } else { est[i] };
        let m = DMatrix::from_fn(d, d, |i, j| c.matrix[idx[i]][idx[j]] * jac(i) * jac(j));
        m.cholesky().map(|ch| ch.l())
    });
    let starts: Vec<Vec<f64>> = (0..walkers)
        .map(|_| loop {
            let x: Vec<f64> = match (&chol, laplace) {
                (Some(l), true) => {
                    // Sum of 12 uniforms − 6: close enough to a standard normal for starts.
                    let z = nalgebra::DVector::from_fn(d, |_, _| {
                        (0..12).map(|_| uniform() + 0.5).sum::<f64>() - 6.0
                    });
                    let step = l * z;
                    centre
                        .iter()
                        .enumerate()
                        .map(|(i, c)| c + step[i])
                        .collect()
                }
                _ => centre.iter().map(|c| c + 0.01 * uniform()).collect(),
            };
            if post.log_density(&x).is_finite() {
                break x;
            }
        })
        .collect();
    let est = like.estimate();
    println!(
        "chi2 at the estimate {:.5} (file {:.5}), prior chi2 {:.4} (file {:.4}), log density {:.4}",
        like.chi2(&est),
        like.chi2_min(),
        like.prior_chi2(&est),
        like.prior_chi2_min(),
        post.log_density(&post.to_coords(&est))
    );
    // Another fit of the same page (e.g. with the friction fixed at the truth): its point.
    if let Some(other) = args.get(5) {
        let o = FitFile::read(Path::new(other))?;
        let v: Vec<f64> = names
            .iter()
            .map(|n| o.params.get(n).unwrap_or(f64::NAN))
            .collect();
        println!(
            "other fit: chi2 {:.5}, prior chi2 {:.4}, log density {:.4}",
            like.chi2(&v),
            like.prior_chi2(&v),
            post.log_density(&post.to_coords(&v))
        );
    }
    let settings = EnsembleSettings {
        walkers,
        steps,
        burn_in,
        seed: 1,
    };
    // DE=p: the differential-evolution move with probability p (else the stretch move alone).
    let moves = std::env::var("DE")
        .ok()
        .and_then(|v| v.parse().ok())
        .map_or(Moves::Stretch, |de| Moves::Mixed { de });
    // SAMPLER=chains: the Laplace-guided Metropolis–Hastings chains (8 chains) instead.
    let mut q = post.proposal()?;
    importance_check(&post, &q);
    // HESS=step: the Laplace approximation from the full Hessian of ln p (central
    // differences at that step) instead of Gauss–Newton's.
    if let Some(h) = std::env::var("HESS")
        .ok()
        .and_then(|v| v.parse::<f64>().ok())
    {
        match post.laplace_full(h) {
            Ok(l) => {
                println!(
                    "full Hessian (step {h}): σ {:?}",
                    l.sd().iter().map(|v| format!("{v:.3}")).collect::<Vec<_>>()
                );
                q.laplace = l;
                importance_check(&post, &q);
            }
            Err(e) => println!("full Hessian (step {h}): {e}"),
        }
    }
    if std::env::var("DIAG").is_ok() {
        diagnose(&post, &like, &q, &names);
        return Ok(());
    }
    let sampler = std::env::var("SAMPLER").unwrap_or_default();
    let t0 = std::time::Instant::now();
    let chains = if sampler == "map" {
        map_chains(&post, &starts, walkers, steps, burn_in)?
    } else if sampler == "chains" {
        let s = ChainSettings {
            chains: 8,
            steps,
            burn_in,
            block: steps + burn_in,
            seed: 1,
        };
        run_chains(&post, &q, &s, None, &|_, _| {})?
    } else {
        run_ensemble_with(&post, &starts, &settings, moves, &|_, _| {})?
    };
    println!("sampling took {:.2} s", t0.elapsed().as_secs_f64());
    per_chain_means(&chains, &names);
    let diag = summarise(&chains.draws);
    let flat = chains.flat();
    let n = flat.len() as f64;
    let mean: Vec<f64> = (0..d)
        .map(|i| flat.iter().map(|x| x[i]).sum::<f64>() / n)
        .collect();
    let sample_cov = DMatrix::from_fn(d, d, |i, j| {
        flat.iter()
            .map(|x| (x[i] - mean[i]) * (x[j] - mean[j]))
            .sum::<f64>()
            / (n - 1.0)
    });
    // The fit file's curvature covariance, in the same order where it has the parameter.
    let curv = fit.covariance.as_ref().map(|c| {
        let idx: Vec<Option<usize>> = names
            .iter()
            .map(|n| c.parameters.iter().position(|m| m == n))
            .collect();
        DMatrix::from_fn(d, d, |i, j| match (idx[i], idx[j]) {
            (Some(a), Some(b)) => c.matrix[a][b],
            _ => f64::NAN,
        })
    });
    let delta_index: Vec<Option<usize>> = names
        .iter()
        .map(|n| unc.names.iter().position(|m| m == n))
        .collect();
    println!(
        "steps {steps} burn-in {burn_in} walkers {walkers} acceptance {:.3}",
        chains.mean_acceptance()
    );
    println!("| parameter | σ ln θ delta | σ curvature | σ samples | R̂ | ESS bulk |");
    println!("|---|---|---|---|---|---|");
    for i in 0..d {
        let ds = delta_index[i].map_or(f64::NAN, |j| unc.sd[j]);
        let cs = curv.as_ref().map_or(f64::NAN, |c| c[(i, i)].sqrt());
        println!(
            "| {} | {ds:.3} | {cs:.3} | {:.3} | {:.3} | {:.0} |",
            names[i],
            sample_cov[(i, i)].sqrt(),
            diag[i].rhat,
            diag[i].ess_bulk
        );
    }
    let corr = |m: &DMatrix<f64>, i: usize, j: usize| m[(i, j)] / (m[(i, i)] * m[(j, j)]).sqrt();
    println!("\ncorrelations (delta C / curvature / samples):");
    for i in 0..d {
        for j in (i + 1)..d {
            let dc = match (delta_index[i], delta_index[j]) {
                (Some(a), Some(b)) => corr(&unc.cov, a, b),
                _ => f64::NAN,
            };
            let cc = curv.as_ref().map_or(f64::NAN, |c| corr(c, i, j));
            let sc = corr(&sample_cov, i, j);
            if dc.abs() > 0.5 || cc.abs() > 0.5 || sc.abs() > 0.5 {
                println!(
                    "  {:>9} {:>9}: {dc:+.3} / {cc:+.3} / {sc:+.3}",
                    names[i], names[j]
                );
            }
        }
    }
    let eig = |m: &DMatrix<f64>| {
        let mut e: Vec<f64> = m
            .clone()
            .symmetric_eigen()
            .eigenvalues
            .iter()
            .copied()
            .collect();
        e.sort_by(f64::total_cmp);
        e.iter()
            .map(|v| format!("{:.2e}", v.max(0.0).sqrt()))
            .collect::<Vec<_>>()
            .join(" ")
    };
    println!(
        "\n√eigenvalues, delta C ({} parameters): {}",
        unc.names.len(),
        eig(&unc.cov)
    );
    if let Some(c) = &curv {
        println!("√eigenvalues, curvature: {}", eig(c));
    }
    println!("√eigenvalues, samples: {}", eig(&sample_cov));
    Ok(())
}

/// Importance sampling from `q`: prints the effective sample size of the weights p/q of 4000
/// draws and the Hill estimate of their tail index k̂ (largest 20 %).
fn importance_check(post: &FitPosterior, q: &TProposal) {
    use rand::SeedableRng;
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(17);
    let mut logw: Vec<f64> = (0..4000)
        .map(|_| {
            let x = q.draw(&mut rng);
            post.log_density(&x) - q.log_q(&x)
        })
        .filter(|v| v.is_finite())
        .collect();
    logw.sort_by(|a, b| b.total_cmp(a));
    let top = logw[0];
    let w: Vec<f64> = logw.iter().map(|v| (v - top).exp()).collect();
    let ess = w.iter().sum::<f64>().powi(2) / w.iter().map(|v| v * v).sum::<f64>();
    let m = logw.len() / 5;
    let k_hat = logw[..m].iter().map(|v| v - logw[m]).sum::<f64>() / m as f64;
    println!(
        "importance sampling from the Laplace t proposal: {} of 4000 draws inside, ESS {ess:.1}, k̂ (Hill, top 20 %) {k_hat:.2}",
        logw.len()
    );
}

/// Each chain's mean of the parameter with the largest R̂.
fn per_chain_means(chains: &Chains, names: &[String]) {
    let diag = summarise(&chains.draws);
    let worst = (0..names.len())
        .max_by(|a, b| diag[*a].rhat.total_cmp(&diag[*b].rhat))
        .unwrap_or(0);
    let means: Vec<String> = chains
        .draws
        .iter()
        .map(|c| {
            format!(
                "{:.3}",
                c.iter().map(|x| x[worst]).sum::<f64>() / c.len() as f64
            )
        })
        .collect();
    println!(
        "per-chain means of {} (R̂ {:.3}): {}",
        names[worst],
        diag[worst].rhat,
        means.join(" ")
    );
}

/// `SAMPLER=map`: a pilot ensemble (`PILOT` steps after as many, default 500), a quadratic
/// transport map fitted to its draws, then `CHAINS` (8) Laplace-style chains in the map's
/// coordinates with a t of the mapped draws' Gaussian; `MAPS` (default 1) refits of the map
/// to the chains' draws.
fn map_chains(
    post: &FitPosterior,
    starts: &[Vec<f64>],
    walkers: usize,
    steps: usize,
    burn_in: usize,
) -> Result<Chains, Box<dyn std::error::Error>> {
    let env = |k: &str, d: usize| {
        std::env::var(k)
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(d)
    };
    let pilot = env("PILOT", 500);
    let t0 = std::time::Instant::now();
    let es = EnsembleSettings {
        walkers,
        steps: pilot,
        burn_in: pilot,
        seed: 1,
    };
    let pc = run_ensemble_with(post, starts, &es, Moves::Mixed { de: 0.8 }, &|_, _| {})?;
    let mut draws = pc.flat();
    let ridge: f64 = std::env::var("RIDGE")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(1e-6);
    let mut out = None;
    for round in 0..env("MAPS", 1) {
        let map = QuadraticMap::fit(&draws, ridge).ok_or("no map")?;
        let zs: Vec<Vec<f64>> = draws.iter().map(|x| map.forward(x)).collect();
        let q = TProposal {
            laplace: gaussian_of(&zs).ok_or("singular")?,
            nu: 5.0,
            scale: env("SCALE10", 12) as f64 / 10.0,
        };
        let mapped = Mapped {
            density: post,
            map: &map,
        };
        let c = ImportanceCheck::of(&mapped, &q, 1000, 3 + round as u64);
        let c2 = ImportanceCheck::of_inside({
            let (_, lw) = ImportanceCheck::weighed(&mapped, &q, 1000, 3 + round as u64);
            lw
        });
        println!(
            "round {round}: {:.2} s, {} draws; k̂ of the mapped t: {:.2} ({} of 1000 inside; over those {:.2}), ESS {:.0}",
            t0.elapsed().as_secs_f64(), draws.len(), c.k_hat, c.inside, c2.k_hat, c.ess
        );
        let s = ChainSettings {
            chains: env("CHAINS", 8),
            steps,
            burn_in,
            block: steps + burn_in,
            seed: 1 + round as u64,
        };
        let zc = if std::env::var("MAPENS").is_ok() {
            let last: Vec<Vec<f64>> = pc
                .draws
                .iter()
                .map(|w| map.forward(w.last().unwrap()))
                .collect();
            let es = EnsembleSettings {
                walkers,
                steps,
                burn_in,
                seed: 1 + round as u64,
            };
            run_ensemble_with(&mapped, &last, &es, Moves::Mixed { de: 0.8 }, &|_, _| {})?
        } else {
            run_chains(&mapped, &q, &s, None, &|_, _| {})?
        };
        let xc = Chains {
            dim: zc.dim,
            draws: zc
                .draws
                .iter()
                .map(|w| w.iter().map(|z| map.inverse(z)).collect())
                .collect(),
            log_density: zc.log_density.clone(),
            acceptance: zc.acceptance.clone(),
        };
        let diag = summarise(&xc.draws);
        let worst = diag.iter().map(|d| d.rhat).fold(0.0, f64::max);
        let ess = diag
            .iter()
            .map(|d| d.ess_bulk.min(d.ess_tail))
            .fold(f64::INFINITY, f64::min);
        println!(
            "  chains: {:.2} s, R̂ ≤ {worst:.3}, ESS ≥ {ess:.0}, acceptance {:.3}",
            t0.elapsed().as_secs_f64(),
            xc.mean_acceptance()
        );
        draws = xc.thinned(8000);
        out = Some(xc);
    }
    Ok(out.ok_or("no rounds")?)
}

/// `DIAG=1`: why the posterior is not its Laplace approximation. (1) Of 4000 draws of the t
/// proposal, how many leave each coordinate's support; (2) ln p along each principal axis
/// of the Laplace covariance at ±0.5…3 σ against the Gaussian's −r²/2, and the roughness at
/// a fine scale (mean |second difference| at steps of 10⁻³ σ and 10⁻² σ over δ²: 1 for the
/// Gaussian, ≫ 1 where ln p is curved beyond it or not smooth); (3) along the wide axes,
/// Σ(J·v)² (the Gauss–Newton curvature) against ½ χ²'' at steps h, and χ² against Σ r².
fn diagnose(post: &FitPosterior, like: &FitLikelihood, q: &TProposal, names: &[String]) {
    use rand::SeedableRng;
    let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(17);
    let b = post.coord_bounds();
    let d = names.len();
    let mut out = vec![(0usize, 0usize); d];
    let mut failed = 0;
    let n = 4000;
    for _ in 0..n {
        let x = q.draw(&mut rng);
        let mut inside = true;
        for i in 0..d {
            if x[i] < b[i].0 {
                out[i].0 += 1;
                inside = false;
            } else if x[i] > b[i].1 {
                out[i].1 += 1;
                inside = false;
            }
        }
        if inside && !post.log_density(&x).is_finite() {
            failed += 1;
        }
    }
    println!(
        "draws of the t outside a bound (below/above), of {n}; {failed} inside with zero density:"
    );
    let mode = &q.laplace.mode;
    let sd = q.laplace.sd();
    for i in 0..d {
        println!(
            "  {:>10}: {:>4} / {:>4}   mode {:+.3} in [{:+.3}, {:+.3}] (σ {:.3}: {:.1} σ / {:.1} σ to the bounds)",
            names[i], out[i].0, out[i].1, mode[i], b[i].0, b[i].1, sd[i],
            (mode[i] - b[i].0) / sd[i], (b[i].1 - mode[i]) / sd[i]
        );
    }
    let cov = &q.laplace.chol * q.laplace.chol.transpose();
    let eig = cov.clone().symmetric_eigen();
    let lp0 = post.log_density(mode);
    println!("ln p − ln p(mode) along the Laplace covariance's principal axes (Gaussian: −r²/2 = −0.125, −0.5, −2, −4.5):");
    println!("| axis σ | largest components | −3σ | −2σ | −1σ | −0.5σ | +0.5σ | +1σ | +2σ | +3σ | rough 1e-3σ | rough 1e-2σ |");
    let mut order: Vec<usize> = (0..d).collect();
    order.sort_by(|a, b| eig.eigenvalues[*a].total_cmp(&eig.eigenvalues[*b]));
    for k in order {
        let s = eig.eigenvalues[k].max(0.0).sqrt();
        let v = eig.eigenvectors.column(k);
        let point = |t: f64| -> Vec<f64> { (0..d).map(|i| mode[i] + t * s * v[i]).collect() };
        let at = |t: f64| post.log_density(&point(t)) - lp0;
        let mut comp: Vec<(usize, f64)> = (0..d).map(|i| (i, v[i])).collect();
        comp.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()));
        let top: Vec<String> = comp[..2]
            .iter()
            .map(|(i, c)| format!("{:+.2} {}", c, names[*i]))
            .collect();
        let vals: Vec<String> = [-3.0, -2.0, -1.0, -0.5, 0.5, 1.0, 2.0, 3.0]
            .iter()
            .map(|r| format!("{:.2}", at(*r)))
            .collect();
        let rough = |delta: f64| {
            let pts: Vec<f64> = (0..22).map(|j| at(0.3 + delta * j as f64)).collect();
            let sd2: f64 = (1..21)
                .map(|j| (pts[j - 1] - 2.0 * pts[j] + pts[j + 1]).abs())
                .sum::<f64>()
                / 20.0;
            sd2 / (delta * delta)
        };
        println!(
            "| {s:.3} | {} | {} | {:.2} | {:.2} |",
            top.join(", "),
            vals.join(" | "),
            rough(1e-3),
            rough(1e-2)
        );
        if s > 0.3 {
            let r_at = |t: f64| {
                like.residuals(&post.to_values(&point(t)))
                    .unwrap_or_default()
            };
            let c_at = |t: f64| like.chi2(&post.to_values(&point(t)));
            for h in [1e-4, 1e-3, 1e-2, 1e-1] {
                let (a, b) = (r_at(h), r_at(-h));
                let jv2: f64 = a
                    .iter()
                    .zip(&b)
                    .map(|(p, m)| ((p - m) / (2.0 * h)).powi(2))
                    .sum();
                let c2 = (c_at(h) - 2.0 * c_at(0.0) + c_at(-h)) / (h * h) / 2.0;
                println!("|   h {h:e}σ: Σ(Jv)² {jv2:.3}, ½χ²'' {c2:.3} |");
            }
            let vals = post.to_values(&point(1.0));
            if let (Ok(c), Ok(r)) = (like.try_chi2(&vals), like.residuals(&vals)) {
                println!(
                    "|   at +1σ: χ² {c:.4}, Σr² {:.4} ({} residuals) |",
                    r.iter().map(|v| v * v).sum::<f64>(),
                    r.len()
                );
            }
        }
    }
}
