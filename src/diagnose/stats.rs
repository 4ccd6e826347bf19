//! Small statistics for the diagnosis: normal and χ² tail probabilities, the Wald–Wolfowitz
//! runs test, a polynomial trend test, and sliding-window bias of residuals that are
//! standard normal under the null hypothesis "the model explains the data to within noise".

/// Standard normal cumulative distribution Φ(z).
fn normal_cdf(z: f64) -> f64 {
    0.5 * erfc(-z / std::f64::consts::SQRT_2)
}

/// Complementary error function, |relative error| < 1.2e-7 everywhere (Numerical Recipes'
/// Chebyshev fit, `erfcc`), enough for p-values.
fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 {
        r
    } else {
        2.0 - r
    }
}

/// Quantile of the standard normal, Φ⁻¹(p), by Acklam's rational approximation
/// ([`crate::numerics::normal::normal_quantile`]) refined by one Halley step.
pub(crate) fn normal_quantile(p: f64) -> f64 {
    let x = crate::numerics::normal::normal_quantile(p);
    if !x.is_finite() {
        return x;
    }
    // One Halley step on Φ(x) − p.
    let e = normal_cdf(x) - p;
    let u = e * (2.0 * std::f64::consts::PI).sqrt() * (x * x / 2.0).exp();
    x - u / (1.0 + x * u / 2.0)
}

/// ln Γ(x) for x > 0 (Lanczos, g = 7, n = 9; ≈ 1e-15 relative).
fn ln_gamma(x: f64) -> f64 {
    const G: [f64; 9] = [
        0.999_999_999_999_809_9,
        676.520_368_121_885_1,
        -1_259.139_216_722_402_8,
        771.323_428_777_653_1,
        -176.615_029_162_140_6,
        12.507_343_278_686_905,
        -0.138_571_095_265_720_12,
        9.984_369_578_019_572e-6,
        1.505_632_735_149_311_6e-7,
    ];
    if x < 0.5 {
        let pi = std::f64::consts::PI;
        return (pi / (pi * x).sin()).ln() - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = G[0];
    let t = x + 7.5;
    for (i, g) in G.iter().enumerate().skip(1) {
        a += g / (x + i as f64);
    }
    0.5 * (2.0 * std::f64::consts::PI).ln() + (x + 0.5) * t.ln() - t + a.ln()
}

/// Upper tail of the χ² distribution with `df` degrees of freedom: P(X > x), through the
/// regularised incomplete gamma function Q(df/2, x/2) (series below a + 1, continued
/// fraction above, as in Numerical Recipes).
pub(crate) fn chi2_sf(x: f64, df: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let a = df / 2.0;
    let x = x / 2.0;
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        let (mut sum, mut del, mut ap) = (1.0 / a, 1.0 / a, a);
        for _ in 0..1000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * x.ln() - gln).exp()
    } else {
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        ((-x + a * x.ln() - gln).exp() * h).clamp(0.0, 1.0)
    }
}

/// Wald–Wolfowitz runs test on the signs of residuals in abscissa order. Returns the z
/// score (negative: fewer runs than chance, i.e. residuals come in systematic blocks) and
/// the one-sided p-value P(Z ≤ z). Zero residuals are skipped. `None` with fewer than ten
/// signs of either kind, where the normal approximation is poor.
pub(crate) fn runs_test(r: &[f64]) -> Option<(f64, f64)> {
    let signs: Vec<bool> = r.iter().filter(|v| **v != 0.0).map(|v| *v > 0.0).collect();
    let n_pos = signs.iter().filter(|s| **s).count() as f64;
    let n_neg = signs.len() as f64 - n_pos;
    if n_pos < 10.0 || n_neg < 10.0 {
        // All of one sign with many points is itself systematic: report it as such.
        if signs.len() >= 20 && (n_pos == 0.0 || n_neg == 0.0) {
            return Some((f64::NEG_INFINITY, 0.0));
        }
        return None;
    }
    let n = n_pos + n_neg;
    let runs = 1.0 + signs.windows(2).filter(|w| w[0] != w[1]).count() as f64;
    let mean = 2.0 * n_pos * n_neg / n + 1.0;
    let var = 2.0 * n_pos * n_neg * (2.0 * n_pos * n_neg - n) / (n * n * (n - 1.0));
    let z = (runs - mean) / var.sqrt();
    Some((z, normal_cdf(z)))
}

/// Trend test: least squares of standard-normal residuals r on Legendre polynomials
/// P_1..P_d of the abscissa scaled to [−1, 1]. With unit noise variance the explained sum
/// of squares is χ²(d) under the null; returns (statistic, p-value).
pub(crate) fn trend_test(x: &[f64], r: &[f64], degree: usize) -> Option<(f64, f64)> {
    let n = x.len();
    if n < 3 * (degree + 1) {
        return None;
    }
    let (lo, hi) = x
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(*v), b.max(*v))
        });
    if hi <= lo {
        return None;
    }
    let cols = degree + 1;
    let mut a = nalgebra::DMatrix::<f64>::zeros(n, cols);
    for (i, xi) in x.iter().enumerate() {
        let u = (2.0 * xi - lo - hi) / (hi - lo);
        let (mut p0, mut p1) = (1.0, u);
        a[(i, 0)] = 1.0;
        if cols > 1 {
            a[(i, 1)] = u;
        }
        for k in 2..cols {
            let p2 = ((2 * k - 1) as f64 * u * p1 - (k - 1) as f64 * p0) / k as f64;
            a[(i, k)] = p2;
            p0 = p1;
            p1 = p2;
        }
    }
    let y = nalgebra::DVector::from_column_slice(r);
    let svd = a.clone().svd(true, true);
    let c = svd.solve(&y, 1e-12).ok()?;
    // Explained by the non-constant terms: fit with all terms minus fit with the mean only.
    let fitted = &a * &c;
    let mean = r.iter().sum::<f64>() / n as f64;
    let ss_full: f64 = fitted.iter().map(|v| v * v).sum();
    let ss_mean = n as f64 * mean * mean;
    let stat = (ss_full - ss_mean).max(0.0);
    Some((stat, chi2_sf(stat, degree as f64)))
}

/// A run of consecutive points (in abscissa order) whose mean residual is far from zero.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Region {
    /// First and last index (inclusive) in the sorted order.
    pub first: usize,
    /// Last index (inclusive).
    pub last: usize,
    /// Largest |mean normalised residual| of any flagged window in the region (σ units),
    /// with its sign.
    pub bias: f64,
    /// z score of that window, mean·√w.
    pub z: f64,
}

/// Window widths tried on a channel of n points: n/20, n/10 and n/5, at least 5 points.
fn window_widths(n: usize) -> Vec<usize> {
    let mut w: Vec<usize> = [n / 20, n / 10, n / 5]
        .into_iter()
        .map(|w| w.max(5))
        .filter(|w| *w <= n)
        .collect();
    w.dedup();
    w
}

/// Number of windows [`biased_regions`] tests on n points (for the Bonferroni correction).
pub(crate) fn window_count(n: usize) -> usize {
    window_widths(n)
        .into_iter()
        .map(|w| (n - w) / (w / 2).max(1) + 1)
        .sum()
}

/// Sliding windows of the widths of [`window_widths`], stride w/2, over residuals `r`
/// (standard normal under the null, in abscissa order). A window whose mean m has
/// |m|·√w > `z_crit` is flagged; overlapping flagged windows of the same sign form a region,
/// which spans those of its windows whose |m| is at least half the largest.
pub(crate) fn biased_regions(r: &[f64], z_crit: f64) -> Vec<Region> {
    let n = r.len();
    let mut prefix = vec![0.0; n + 1];
    for (i, v) in r.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
    }
    let mut flagged: Vec<(usize, usize, f64, f64)> = Vec::new();
    for w in window_widths(n) {
        let stride = (w / 2).max(1);
        let mut start = 0;
        while start + w <= n {
            let m = (prefix[start + w] - prefix[start]) / w as f64;
            let z = m * (w as f64).sqrt();
            if z.abs() > z_crit {
                flagged.push((start, start + w - 1, m, z));
            }
            start += stride;
        }
    }
    flagged.sort_by(|a, b| a.0.cmp(&b.0).then(a.1.cmp(&b.1)));
    // Connected groups of flagged windows of one sign.
    let mut groups: Vec<Vec<(usize, usize, f64, f64)>> = Vec::new();
    for w in flagged {
        let joins = |g: &Vec<(usize, usize, f64, f64)>| {
            let (lo, hi) = g
                .iter()
                .fold((usize::MAX, 0), |(a, b), v| (a.min(v.0), b.max(v.1)));
            w.0 <= hi + 1 && w.1 + 1 >= lo && g[0].2.signum() == w.2.signum()
        };
        match groups.iter_mut().find(|g| joins(g)) {
            Some(g) => g.push(w),
            None => groups.push(vec![w]),
        }
    }
    // A region spans the windows of its group whose mean is at least half the largest, so
    // that wide windows which merely contain a short bias do not widen it.
    groups
        .into_iter()
        .map(|g| {
            let top = g
                .iter()
                .max_by(|a, b| a.2.abs().total_cmp(&b.2.abs()))
                .copied()
                .expect("non-empty group");
            let strong = g.iter().filter(|w| w.2.abs() >= 0.5 * top.2.abs());
            let (first, last) = strong.fold((usize::MAX, 0), |(a, b), w| (a.min(w.0), b.max(w.1)));
            Region {
                first,
                last,
                bias: top.2,
                z: top.3,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use rand_xoshiro::Xoshiro256PlusPlus;

    #[test]
    fn tail_probabilities_match_tables() {
        assert!((normal_cdf(1.959_964) - 0.975).abs() < 1e-6);
        assert!((normal_quantile(0.975) - 1.959_964).abs() < 1e-5);
        assert!((normal_quantile(1e-6) + 4.753_424).abs() < 1e-4);
        // χ²(1) at 3.841 is 0.05; χ²(16) at 39.252 is 0.001.
        assert!((chi2_sf(3.841_459, 1.0) - 0.05).abs() < 1e-5);
        assert!((chi2_sf(39.252, 16.0) - 0.001).abs() < 1e-5);
        assert!((chi2_sf(2.0, 2.0) - (-1.0f64).exp()).abs() < 1e-9);
        assert!((ln_gamma(5.0) - 24f64.ln()).abs() < 1e-12);
    }

    /// At the 5% level on pure noise, each test fires about 5% of the time.
    #[test]
    fn trend_and_runs_tests_are_calibrated() {
        let d = Normal::new(0.0, 1.0).unwrap();
        let x: Vec<f64> = (0..600).map(|i| i as f64).collect();
        let mut low = 0;
        let mut rl = 0;
        for seed in 0..400 {
            let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
            let r: Vec<f64> = (0..600).map(|_| d.sample(&mut rng)).collect();
            if trend_test(&x, &r, 3).unwrap().1 < 0.05 {
                low += 1;
            }
            if runs_test(&r).unwrap().1 < 0.05 {
                rl += 1;
            }
        }
        assert!(low < 40 && rl < 40);
    }

    #[test]
    fn noise_passes_and_a_bump_is_found() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(4);
        let d = Normal::new(0.0, 1.0).unwrap();
        let n = 600;
        let x: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let r: Vec<f64> = (0..n).map(|_| d.sample(&mut rng)).collect();
        let z_crit = normal_quantile(1.0 - 0.01 / (2.0 * window_count(n) as f64));
        assert!(biased_regions(&r, z_crit).is_empty());
        assert!(runs_test(&r).unwrap().1 > 0.01);
        let trend = trend_test(&x, &r, 3).unwrap();
        assert!(trend.1 > 0.01, "{trend:?}");
        // A bias of one σ over 60 points.
        let mut bumped = r.clone();
        for v in &mut bumped[400..460] {
            *v += 1.0;
        }
        let regions = biased_regions(&bumped, z_crit);
        assert_eq!(regions.len(), 1, "{regions:?}");
        assert!(
            regions[0].first >= 360 && regions[0].last <= 500,
            "{regions:?}"
        );
        assert!(regions[0].bias > 0.7);
        // A slow drift of ±1σ: fewer sign changes than chance, and a trend.
        let drift: Vec<f64> = r
            .iter()
            .enumerate()
            .map(|(i, v)| v + (i as f64 / n as f64 * 6.0).sin())
            .collect();
        assert!(runs_test(&drift).unwrap().1 < 1e-2);
        assert!(trend_test(&x, &drift, 3).unwrap().1 < 1e-3);
    }
}
