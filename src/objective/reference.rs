//! Reference responses (paper §4.2; docs/model.md, "Reference experiments"): each measured
//! channel of each experiment is described by a least-squares polynomial of its abscissa,
//! valid only over the measured range. The cost ([`crate::objective::cost`]) compares
//! simulations against these polynomials.
//!
//! # Method
//!
//! * **Basis.** Chebyshev polynomials T_k(u) on the abscissa scaled to u ∈ [−1, 1],
//!   u = (2x − x_min − x_max)/(x_max − x_min). On data spread over the interval their
//!   design matrix is close to orthogonal, so a degree-8 fit stays well conditioned whatever
//!   the abscissa's unit (Pa, rad/s or log10 m³/(s·Pa)).
//! * **Solver.** Householder QR of the design matrix A = Q·R (nalgebra), coefficients from
//!   R·c = Qᵀ·y. Never the normal equations (they square the condition number). Because QR
//!   is not pivoted, the first p columns of Q span the polynomials of degree p − 1, so one
//!   factorisation gives the fits of every degree.
//! * **Degree.** Leave-one-out cross-validation through the hat matrix: the LOO residual of
//!   point i is e_i/(1 − h_ii) with h_ii = Σ_{j<p} Q_ij², exact for linear least squares
//!   (PRESS). Degrees 1 … min(8, ⌊(n − 1)/3⌋) are tried; the choice is the smallest degree
//!   whose mean squared LOO residual is within one standard error of the best (the
//!   "one-standard-error rule", with the standard error √(2/n)·mean of Gaussian residuals),
//!   which keeps the reference from chasing noise.
//! * **Noise.** σ = √(RSS/(n − p)), the RMS residual with the degrees-of-freedom correction
//!   (pooled over pieces: ΣRSS/(Σn − Σp)), in the channel's SI unit. [`Reference::sigma`]
//!   never returns less than max|y|/4096 (the resolution of a 12-bit converter), so that
//!   noise-free curves (a digitised datasheet, synthetic data without noise) do not get an
//!   infinite weight in the cost.
//! * **Jumps.** A pressure ramp can hold the motor at standstill until it breaks away and
//!   jumps to speed. One polynomial would smear that jump. With at least
//!   `MIN_POINTS_FOR_SPLIT` points, a change-point search tries split positions on a
//!   grid of ≈100, then around the best a tenth of the grid step at a time down to single
//!   points (so its time is linear in n), and fits both pieces with their own CV-chosen
//!   degree; a segment longer than 4096 points is searched on every s-th point and the
//!   split found is judged on all of them. A split is accepted only when it is clearly better than one piece:
//!   PRESS must fall by at least the factor `SPLIT_GAIN` *and* by more than a BIC-like
//!   penalty, n·ln(PRESS₁/PRESS₂) > (p₂ − p₁ + 1)·ln n. Splitting is repeated on the pieces
//!   (binary segmentation) up to [`ReferenceOptions::max_pieces`]. Points in the middle of the
//!   jump (the rotor accelerating while the pressure barely moves) belong to neither curve:
//!   of the points next to a split, those more than 4 prediction standard deviations from
//!   a fit of the rest of their piece are dropped (repeatedly, refitting in between). A
//!   piece's valid range ends at its last kept point, which leaves a gap where
//!   [`Reference::eval`] returns `None`.

use crate::data::dataset::{DataError, ExperimentData, Kind, Recording};
use crate::sim::experiment::AbscissaSpec;
use crate::units::{Quantity, Unit};
use nalgebra::{DMatrix, DVector};

/// Highest polynomial degree tried.
const MAX_DEGREE: usize = 8;
/// Fewest points a reference (or one piece of it) is fitted to: degree 1 plus LOO needs 3,
/// one more keeps the noise estimate meaningful.
const MIN_POINTS: usize = crate::data::dataset::MIN_ROWS;
/// Fewest points on which a split into pieces is considered.
const MIN_POINTS_FOR_SPLIT: usize = 40;
/// Factor by which the LOO error (PRESS) must fall for a split to be accepted.
const SPLIT_GAIN: f64 = 1.5;
/// Distance from the rest of its piece, in prediction standard deviations, beyond which a
/// point next to a split is taken as part of the jump.
const TRIM_SIGMAS: f64 = 4.0;
/// Rounds of trimming (each refits the pieces).
const TRIM_ROUNDS: usize = 3;

/// How references are fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReferenceOptions {
    /// Highest degree tried (further limited to ⌊(n − 1)/3⌋ for n points).
    pub max_degree: usize,
    /// Most pieces a reference may be split into (1: never split).
    pub max_pieces: usize,
}

impl Default for ReferenceOptions {
    /// Degree up to 8, at most 3 pieces.
    fn default() -> Self {
        Self {
            max_degree: MAX_DEGREE,
            max_pieces: 3,
        }
    }
}

/// Why a reference could not be fitted.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ReferenceError {
    /// The polynomial of this degree is not determined by the points.
    #[error("degree {0} is not determined by the data")]
    Undetermined(usize),
    /// Abscissa and ordinates differ in length.
    #[error("{0} abscissa values but {1} ordinates")]
    LengthMismatch(usize, usize),
    /// Fewer points than the fit needs.
    #[error("{got} points are too few (need at least {min})")]
    TooFew {
        /// Points given.
        got: usize,
        /// Points needed.
        min: usize,
    },
    /// A point (1-based) with a NaN or infinite coordinate.
    #[error("point {0} is not finite")]
    NotFinite(usize),
    /// Every abscissa is the same.
    #[error("abscissa does not span a range")]
    NoRange,
    /// Leave-one-out cross-validation has no degree to score.
    #[error("no degree can be cross-validated")]
    NoDegree,
    /// The selected degree could not be fitted.
    #[error("degree selection failed")]
    SelectionFailed,
}

/// Chebyshev polynomials T_0 … T_{m−1} at u, by the recurrence T_{k+1} = 2u·T_k − T_{k−1}.
fn chebyshev_row(u: f64, m: usize, out: &mut [f64]) {
    for k in 0..m {
        out[k] = match k {
            0 => 1.0,
            1 => u,
            _ => 2.0 * u * out[k - 1] - out[k - 2],
        };
    }
}

/// One least-squares polynomial over a contiguous range of the abscissa.
#[derive(Debug, Clone, PartialEq)]
pub struct Piece {
    /// Smallest abscissa of the fitted points (SI).
    pub x_min: f64,
    /// Largest abscissa of the fitted points (SI).
    pub x_max: f64,
    /// Polynomial degree.
    pub degree: usize,
    /// Chebyshev coefficients c_k of y(x) = Σ c_k·T_k(u), u = (2x − x_min − x_max)/(x_max − x_min);
    /// y in the channel's SI unit.
    coeffs: Vec<f64>,
    /// Points fitted.
    pub n: usize,
    /// Residual sum of squares Σ(y − ŷ)², SI unit squared.
    rss: f64,
    /// Leave-one-out sum of squares Σ(e_i/(1 − h_ii))², SI unit squared.
    press: f64,
}

impl Piece {
    /// Maps x to u ∈ [−1, 1] over the piece's range (u = 0 when the range is a point).
    fn scaled(&self, x: f64) -> f64 {
        scale(x, self.x_min, self.x_max)
    }

    /// The polynomial at x (Clenshaw's recurrence), whether or not x is in range.
    pub fn value(&self, x: f64) -> f64 {
        let u = self.scaled(x);
        let (mut b1, mut b2) = (0.0, 0.0);
        for &c in self.coeffs.iter().skip(1).rev() {
            let b0 = c + 2.0 * u * b1 - b2;
            b2 = b1;
            b1 = b0;
        }
        self.coeffs.first().copied().unwrap_or(0.0) + u * b1 - b2
    }

    /// Whether x lies in the piece's range [x_min, x_max].
    pub fn contains(&self, x: f64) -> bool {
        x >= self.x_min && x <= self.x_max
    }

    /// Least-squares fit of exactly this degree to (x, y) (no degree selection).
    pub fn fit(x: &[f64], y: &[f64], degree: usize) -> Result<Piece, ReferenceError> {
        check_points(x, y, degree + 2)?;
        let qr = QrFit::new(x, y, degree + 1)?;
        qr.piece(degree).ok_or(ReferenceError::Undetermined(degree))
    }
}

fn scale(x: f64, lo: f64, hi: f64) -> f64 {
    if hi > lo {
        (2.0 * x - lo - hi) / (hi - lo)
    } else {
        0.0
    }
}

fn check_points(x: &[f64], y: &[f64], min: usize) -> Result<(), ReferenceError> {
    if x.len() != y.len() {
        return Err(ReferenceError::LengthMismatch(x.len(), y.len()));
    }
    if x.len() < min {
        return Err(ReferenceError::TooFew { got: x.len(), min });
    }
    if let Some(i) = (0..x.len()).find(|&i| !(x[i].is_finite() && y[i].is_finite())) {
        return Err(ReferenceError::NotFinite(i + 1));
    }
    Ok(())
}

/// A QR factorisation of the Chebyshev design matrix with m columns, from which the fit of
/// every degree < m follows.
struct QrFit<'a> {
    x: &'a [f64],
    y: &'a [f64],
    lo: f64,
    hi: f64,
    q: DMatrix<f64>,
    r: DMatrix<f64>,
    /// Qᵀy.
    qty: DVector<f64>,
    /// Number of leading columns that are numerically independent.
    rank: usize,
}

impl<'a> QrFit<'a> {
    fn new(x: &'a [f64], y: &'a [f64], m: usize) -> Result<Self, ReferenceError> {
        let n = x.len();
        let m = m.min(n).max(1);
        let (lo, hi) = min_max(x);
        if hi.partial_cmp(&lo) != Some(std::cmp::Ordering::Greater) {
            return Err(ReferenceError::NoRange);
        }
        let mut a = DMatrix::<f64>::zeros(n, m);
        let mut row = vec![0.0; m];
        for i in 0..n {
            chebyshev_row(scale(x[i], lo, hi), m, &mut row);
            for k in 0..m {
                a[(i, k)] = row[k];
            }
        }
        let qr = a.qr();
        let q = qr.q();
        let r = qr.r();
        let qty = q.tr_mul(&DVector::from_column_slice(y));
        let r00 = r[(0, 0)].abs();
        let rank = (0..m)
            .take_while(|&k| r[(k, k)].abs() > 1e-10 * r00)
            .count();
        Ok(Self {
            x,
            y,
            lo,
            hi,
            q,
            r,
            qty,
            rank,
        })
    }

    /// Residuals and hat-matrix diagonal of the fit with p columns.
    fn residuals(&self, p: usize) -> (Vec<f64>, Vec<f64>) {
        let n = self.x.len();
        let mut e = self.y.to_vec();
        let mut h = vec![0.0; n];
        for k in 0..p {
            let z = self.qty[k];
            for i in 0..n {
                let qik = self.q[(i, k)];
                e[i] -= qik * z;
                h[i] += qik * qik;
            }
        }
        (e, h)
    }

    /// LOO residuals e_i/(1 − h_ii) of the fit with p columns (None where h_ii ≈ 1).
    fn loo(&self, p: usize) -> Option<(Vec<f64>, f64)> {
        let (e, h) = self.residuals(p);
        let rss = e.iter().map(|v| v * v).sum();
        let loo = e
            .iter()
            .zip(&h)
            .map(|(e, h)| (1.0 - h > 1e-9).then(|| e / (1.0 - h)))
            .collect::<Option<Vec<f64>>>()?;
        Some((loo, rss))
    }

    /// The fitted piece of a degree (None beyond the numerical rank).
    fn piece(&self, degree: usize) -> Option<Piece> {
        let p = degree + 1;
        if p > self.rank || p > self.x.len() {
            return None;
        }
        // Back substitution R[:p,:p]·c = (Qᵀy)[:p].
        let mut c = vec![0.0; p];
        for k in (0..p).rev() {
            let known: f64 = (k + 1..p).map(|j| self.r[(k, j)] * c[j]).sum();
            c[k] = (self.qty[k] - known) / self.r[(k, k)];
        }
        let (e, _) = self.residuals(p);
        let (loo_press, rss) = match self.loo(p) {
            Some((l, rss)) => (l.iter().map(|v| v * v).sum(), rss),
            None => (f64::INFINITY, e.iter().map(|v| v * v).sum()),
        };
        Some(Piece {
            x_min: self.lo,
            x_max: self.hi,
            degree,
            coeffs: c,
            n: self.x.len(),
            rss,
            press: loo_press,
        })
    }
}

fn min_max(v: &[f64]) -> (f64, f64) {
    v.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), x| {
            (a.min(*x), b.max(*x))
        })
}

/// Highest degree allowed for n points: below n/3 and at most `max_degree`.
fn degree_cap(n: usize, max_degree: usize) -> usize {
    (n.saturating_sub(1) / 3).min(max_degree)
}

/// Result of the degree search on one range of points.
struct Selected {
    piece: Piece,
    /// Smallest PRESS over the degrees tried (the change-point search compares these).
    best_press: f64,
}

/// Fits degrees 1 … cap and picks one by LOO cross-validation with the one-standard-error
/// rule (see the module documentation). `x` sorted or not.
fn select(x: &[f64], y: &[f64], max_degree: usize) -> Result<Selected, ReferenceError> {
    check_points(x, y, MIN_POINTS)?;
    let n = x.len();
    let cap = degree_cap(n, max_degree).max(1);
    let qr = QrFit::new(x, y, cap + 1)?;
    if qr.rank < 2 {
        return Err(ReferenceError::NoRange);
    }
    let scale2 = y.iter().map(|v| v * v).sum::<f64>() / n as f64;
    // (degree, mean squared LOO residual)
    let mut scores: Vec<(usize, f64)> = Vec::new();
    for d in 1..=cap.min(qr.rank - 1) {
        if let Some((loo, _)) = qr.loo(d + 1) {
            scores.push((d, loo.iter().map(|v| v * v).sum::<f64>() / n as f64));
        }
    }
    let Some(&(_, best)) = scores.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
        return Err(ReferenceError::NoDegree);
    };
    // One standard error of a mean of n squared Gaussian residuals is √(2/n) of that mean.
    // (The Gaussian value, not the sample one: where the residuals are lack of fit rather
    // than noise, as on a noise-free curve, their squares are heavy-tailed and the sample
    // standard error would excuse too low a degree.) Differences below 1e-9 of the
    // signal's RMS are rounding, not information.
    let threshold = best * (1.0 + (2.0 / n as f64).sqrt()) + 1e-18 * scale2;
    let degree = scores
        .iter()
        .find(|s| s.1 <= threshold)
        .map(|s| s.0)
        .unwrap_or(1);
    let piece = qr.piece(degree).ok_or(ReferenceError::SelectionFailed)?;
    Ok(Selected {
        piece,
        best_press: best * n as f64,
    })
}

/// A reference response: one polynomial, or several over disjoint ranges when the data
/// jump. Abscissa and ordinate in SI.
#[derive(Debug, Clone, PartialEq)]
pub struct Reference {
    pieces: Vec<Piece>,
    /// Pooled dof-corrected RMS residual, SI.
    sigma_residual: f64,
    /// Lower bound on σ: max|y|/4096, SI.
    sigma_floor: f64,
    r_squared: f64,
    /// Points given (including any dropped at a jump).
    n: usize,
}

impl Reference {
    /// Fits a reference to measured points (any order; see the module documentation).
    pub fn fit(
        x: &[f64],
        y: &[f64],
        options: &ReferenceOptions,
    ) -> Result<Reference, ReferenceError> {
        check_points(x, y, MIN_POINTS)?;
        let n = x.len();
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|a, b| x[*a].total_cmp(&x[*b]));
        let xs: Vec<f64> = order.iter().map(|&i| x[i]).collect();
        let ys: Vec<f64> = order.iter().map(|&i| y[i]).collect();
        let md = options.max_degree.max(1);

        // Binary segmentation: split the segment whose best split gains most, while any
        // split is accepted; after each split, drop the jump points next to it (they take
        // no part in later searches or fits).
        let mut keep = vec![true; n];
        let mut segments: Vec<IndexRange> = vec![(0, n)];
        let min_piece = (n / 40).max(10);
        while segments.len() < options.max_pieces.max(1) && n >= MIN_POINTS_FOR_SPLIT {
            let mut best: Option<(usize, usize, f64)> = None; // (segment index, split, gain)
            for (si, &seg) in segments.iter().enumerate() {
                let (idx, sx, sy) = kept(&xs, &ys, &keep, seg);
                if let Some((k, gain)) = best_split(&sx, &sy, md, min_piece) {
                    if best.is_none_or(|(_, _, g)| gain > g) {
                        best = Some((si, idx[k], gain));
                    }
                }
            }
            let Some((si, k, _)) = best else { break };
            let (a, b) = segments[si];
            trim_split(&xs, &ys, &mut keep, (a, k), (k, b), md)?;
            segments.splice(si..=si, [(a, k), (k, b)]);
        }
        let mut used = Vec::with_capacity(n);
        let mut pieces = Vec::with_capacity(segments.len());
        for &seg in &segments {
            let (_, sx, sy) = kept(&xs, &ys, &keep, seg);
            pieces.push(select(&sx, &sy, md)?.piece);
            used.extend(sy);
        }

        let sigma_residual = pooled_sigma(&pieces);
        let mean = used.iter().sum::<f64>() / used.len() as f64;
        let tss: f64 = used.iter().map(|v| (v - mean).powi(2)).sum();
        let rss: f64 = pieces.iter().map(|p| p.rss).sum();
        let r_squared = if tss > 0.0 { 1.0 - rss / tss } else { 1.0 };
        let ymax = ys.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        Ok(Reference {
            pieces,
            sigma_residual,
            sigma_floor: (ymax / 4096.0).max(f64::MIN_POSITIVE),
            r_squared,
            n,
        })
    }

    /// The reference of stated points (a catalogue's curve read off a printed page): σ is
    /// the reading tolerance, `tolerance`·`full_scale` (the curve's full scale, SI: max|y|
    /// where the page prints a value other than 0), not a noise estimate; with fewer than
    /// `MIN_POINTS` distinct abscissae the polynomial has degree (distinct − 1) through them
    /// (a single point is a constant over a point-wide range), otherwise it is fitted as
    /// any reference is.
    pub fn stated(
        x: &[f64],
        y: &[f64],
        options: &ReferenceOptions,
        tolerance: f64,
        full_scale: f64,
    ) -> Result<Reference, ReferenceError> {
        let ymax = full_scale;
        let mut distinct: Vec<f64> = x.to_vec();
        distinct.sort_by(f64::total_cmp);
        distinct.dedup();
        let mut reference = if distinct.len() >= MIN_POINTS {
            Reference::fit(x, y, options)?
        } else {
            check_points(x, y, 1)?;
            let degree = distinct.len() - 1;
            let piece = if degree == 0 {
                let mean = y.iter().sum::<f64>() / y.len() as f64;
                Piece {
                    x_min: distinct[0],
                    x_max: distinct[0],
                    degree: 0,
                    coeffs: vec![mean],
                    n: y.len(),
                    rss: y.iter().map(|v| (v - mean).powi(2)).sum(),
                    press: 0.0,
                }
            } else {
                let qr = QrFit::new(x, y, degree + 1)?;
                qr.piece(degree)
                    .ok_or(ReferenceError::Undetermined(degree))?
            };
            Reference {
                pieces: vec![piece],
                sigma_residual: 0.0,
                sigma_floor: 0.0,
                r_squared: 1.0,
                n: x.len(),
            }
        };
        reference.sigma_residual = tolerance * ymax;
        reference.sigma_floor = (ymax / 4096.0).max(f64::MIN_POSITIVE);
        Ok(reference)
    }

    /// The reference at x (SI), or `None` outside the measured range or in a gap between
    /// pieces.
    pub fn eval(&self, x: f64) -> Option<f64> {
        self.pieces
            .iter()
            .find(|p| p.contains(x))
            .map(|p| p.value(x))
    }

    /// Noise level σ used to normalise the cost, SI: the pooled dof-corrected RMS residual,
    /// but at least max|y|/4096.
    pub fn sigma(&self) -> f64 {
        self.sigma_residual.max(self.sigma_floor)
    }

    /// Pooled dof-corrected RMS residual √(ΣRSS/(Σn − Σp)), SI, without the floor.
    pub fn sigma_residual(&self) -> f64 {
        self.sigma_residual
    }

    /// Coefficient of determination 1 − RSS/TSS over the fitted points.
    pub fn r_squared(&self) -> f64 {
        self.r_squared
    }

    /// The pieces in increasing abscissa (one unless the data jump).
    pub fn pieces(&self) -> &[Piece] {
        &self.pieces
    }

    /// The highest degree of any piece.
    pub fn degree(&self) -> usize {
        self.pieces.iter().map(|p| p.degree).max().unwrap_or(0)
    }

    /// Overall valid range [x_min, x_max] (SI); gaps between pieces are not valid.
    pub fn range(&self) -> (f64, f64) {
        (
            self.pieces.first().map_or(f64::NAN, |p| p.x_min),
            self.pieces.last().map_or(f64::NAN, |p| p.x_max),
        )
    }

    /// Number of points given to the fit.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Number of points the pieces were fitted to (fewer than [`Reference::n`] when jump
    /// points were dropped).
    pub fn n_fitted(&self) -> usize {
        self.pieces.iter().map(|p| p.n).sum()
    }
}

fn pooled_sigma(pieces: &[Piece]) -> f64 {
    let rss: f64 = pieces.iter().map(|p| p.rss).sum();
    let dof: usize = pieces
        .iter()
        .map(|p| p.n.saturating_sub(p.degree + 1))
        .sum();
    (rss / dof.max(1) as f64).sqrt()
}

/// Points at most in a split search: a longer segment is searched on every s-th point
/// (its position found to within s points of the 1/`SEARCH_POINTS` of its length), then the
/// split is judged on all points. Searching every point of a 100 MB recording took minutes;
/// recordings of up to this many points (all shipped ones) are searched as before.
const SEARCH_POINTS: usize = 4096;

/// The best single split of a segment (index k: left [0, k), right [k, n)) and its gain
/// PRESS₁/PRESS₂, if it passes the acceptance test of the module documentation.
fn best_split(x: &[f64], y: &[f64], max_degree: usize, min_piece: usize) -> Option<(usize, f64)> {
    let n = x.len();
    if n < 2 * min_piece || n < MIN_POINTS_FOR_SPLIT {
        return None;
    }
    let whole = select(x, y, max_degree).ok()?;
    let (k, press2, p2) = if n <= SEARCH_POINTS {
        search_split(x, y, max_degree, min_piece)?
    } else {
        let stride = n.div_ceil(SEARCH_POINTS);
        let tx: Vec<f64> = x.iter().step_by(stride).copied().collect();
        let ty: Vec<f64> = y.iter().step_by(stride).copied().collect();
        let (kt, _, _) = search_split(&tx, &ty, max_degree, min_piece.div_ceil(stride))?;
        // Point kt of the thinned segment is point kt·stride of the whole; a split between
        // equal abscissae moves to the next distinct one.
        let mut k = kt * stride;
        while k < n - min_piece && x[k] <= x[k - 1] {
            k += 1;
        }
        let (press, p) = split_press(x, y, max_degree, k)?;
        (k, press, p)
    };
    let press1 = whole.best_press;
    let p1 = whole.piece.degree + 1;
    if press2 <= 0.0 {
        return (press1 > 0.0).then_some((k, f64::INFINITY));
    }
    let gain = press1 / press2;
    let penalty = (p2 as f64 - p1 as f64 + 1.0).max(1.0) * (n as f64).ln();
    (gain >= SPLIT_GAIN && n as f64 * gain.ln() > penalty).then_some((k, gain))
}

/// PRESS of the two pieces split at k, and their number of coefficients.
fn split_press(x: &[f64], y: &[f64], max_degree: usize, k: usize) -> Option<(f64, usize)> {
    let l = select(&x[..k], &y[..k], max_degree).ok()?;
    let r = select(&x[k..], &y[k..], max_degree).ok()?;
    Some((
        l.best_press + r.best_press,
        l.piece.degree + r.piece.degree + 2,
    ))
}

/// The split of least PRESS with pieces of at least `min_piece` points: a scan of some
/// hundred positions, then refined around the best a tenth of the step at a time: each
/// level costs some twenty fits, so the search stays linear in n (refining at every index
/// of a step cost n/50 fits of n points: quadratic). A step of 10 or less is refined at
/// every index in one level, as before.
fn search_split(
    x: &[f64],
    y: &[f64],
    max_degree: usize,
    min_piece: usize,
) -> Option<(usize, f64, usize)> {
    let n = x.len();
    if n < 2 * min_piece || min_piece == 0 {
        return None;
    }
    let (lo, hi) = (min_piece, n - min_piece);
    let mut best: Option<(usize, f64, usize)> = None;
    let consider = |k: usize, best: &mut Option<(usize, f64, usize)>| {
        // A split between equal abscissae would leave overlapping ranges.
        if x[k] <= x[k - 1] {
            return;
        }
        if let Some((press, p)) = split_press(x, y, max_degree, k) {
            if best.is_none_or(|(_, bp, _)| press < bp) {
                *best = Some((k, press, p));
            }
        }
    };
    let mut step = ((hi - lo) / 100).max(1);
    for k in (lo..=hi).step_by(step) {
        consider(k, &mut best);
    }
    while step > 1 {
        let Some((k0, _, _)) = best else { break };
        let fine = (step / 10).max(1);
        let (from, to) = (k0.saturating_sub(step - 1).max(lo), (k0 + step - 1).min(hi));
        let mut k = k0 - (k0 - from) / fine * fine;
        while k <= to {
            consider(k, &mut best);
            k += fine;
        }
        step = fine;
    }
    best
}

/// A half-open range [start, end) of indices into the sorted points.
type IndexRange = (usize, usize);

/// The kept points of a sorted range: their indices, abscissae and ordinates.
fn kept(
    xs: &[f64],
    ys: &[f64],
    keep: &[bool],
    (a, b): IndexRange,
) -> (Vec<usize>, Vec<f64>, Vec<f64>) {
    let idx: Vec<usize> = (a..b).filter(|&i| keep[i]).collect();
    let x = idx.iter().map(|&i| xs[i]).collect();
    let y = idx.iter().map(|&i| ys[i]).collect();
    (idx, x, y)
}

/// Drops the points of a jump next to a split, left = [a, k), right = [k, b). For each
/// piece, the min(20, n/8) kept points nearest the split form a window; the piece's other
/// points are fitted (degree by CV), and a window point goes if it lies more than
/// `TRIM_SIGMAS` prediction standard deviations √(σ² + var ŷ(x)) from that fit. Fitting
/// without the window keeps a polynomial from bending towards the jump and hiding it; the
/// prediction variance accounts for the extrapolation. Up to `TRIM_ROUNDS` rounds. Points
/// dropped this way may lie among kept ones (the abscissa is noisy too, so a jump point
/// can sort in among the standstill points); a piece's valid range ends at its last kept
/// point.
fn trim_split(
    xs: &[f64],
    ys: &[f64],
    keep: &mut [bool],
    left: IndexRange,
    right: IndexRange,
    max_degree: usize,
) -> Result<(), ReferenceError> {
    for _round in 0..TRIM_ROUNDS {
        let mut changed = false;
        for (seg, near_end) in [(left, true), (right, false)] {
            let (idx, sx, sy) = kept(xs, ys, keep, seg);
            let len = idx.len();
            let m = (len / 8).min(20);
            let (window, inner) = if near_end {
                (len - m..len, 0..len - m)
            } else {
                (0..m, m..len)
            };
            let Ok(fit) = InteriorFit::new(&sx[inner.clone()], &sy[inner], max_degree) else {
                continue;
            };
            for j in window {
                if (sy[j] - fit.value(sx[j])).abs() > TRIM_SIGMAS * fit.prediction_sd(sx[j]) {
                    keep[idx[j]] = false;
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    Ok(())
}

/// A CV-selected fit with what is needed for prediction intervals.
struct InteriorFit {
    piece: Piece,
    /// R[:p,:p] of the design matrix's QR.
    r: DMatrix<f64>,
    /// √(RSS/(n − p)).
    sigma: f64,
}

impl InteriorFit {
    fn new(x: &[f64], y: &[f64], max_degree: usize) -> Result<Self, ReferenceError> {
        let piece = select(x, y, max_degree)?.piece;
        let p = piece.degree + 1;
        let qr = QrFit::new(x, y, p)?;
        let sigma = (piece.rss / x.len().saturating_sub(p).max(1) as f64).sqrt();
        Ok(Self {
            r: qr.r.view((0, 0), (p, p)).into_owned(),
            piece,
            sigma,
        })
    }

    fn value(&self, x: f64) -> f64 {
        self.piece.value(x)
    }

    /// √(σ² + var ŷ(x)) with var ŷ = σ²·‖R⁻ᵀ·t(x)‖², t(x) the basis row at x.
    fn prediction_sd(&self, x: f64) -> f64 {
        let p = self.r.nrows();
        let mut t = vec![0.0; p];
        chebyshev_row(self.piece.scaled(x), p, &mut t);
        // Forward substitution Rᵀ·w = t.
        let mut w = vec![0.0; p];
        for k in 0..p {
            let known: f64 = (0..k).map(|j| self.r[(j, k)] * w[j]).sum();
            w[k] = (t[k] - known) / self.r[(k, k)];
        }
        let leverage: f64 = w.iter().map(|v| v * v).sum();
        self.sigma * (1.0 + leverage).sqrt()
    }
}

/// What a reference's abscissa is: a recorded column, possibly on a log10 scale.
#[derive(Debug, Clone, PartialEq)]
pub struct Abscissa {
    /// The recorded quantity.
    pub quantity: Quantity,
    /// The column's name as written in the file.
    pub column: String,
    /// The unit of the column.
    pub unit: Unit,
    /// The abscissa is log10 of the SI value (the outlet throttle's conductance).
    pub log10: bool,
}

impl Abscissa {
    /// The abscissa of an experiment kind: speed (datasheet), port-1 pressure (pressure
    /// ramp), log10 of the port-2 conductance (outlet throttle).
    pub fn of(kind: Kind, rec: &Recording) -> Result<Abscissa, DataError> {
        let AbscissaSpec { quantity, log10 } = kind.model().abscissa();
        rec.values(quantity)?;
        let c = rec.column(quantity).expect("checked above");
        Ok(Abscissa {
            quantity,
            column: c.name.clone(),
            unit: c.unit,
            log10,
        })
    }

    /// The measured abscissa of every row, SI (log10 of SI where `log10`).
    pub fn measured(&self, rec: &Recording) -> Result<Vec<f64>, DataError> {
        let v = rec.values(self.quantity)?;
        Ok(if self.log10 {
            v.iter().map(|c| c.log10()).collect()
        } else {
            v.to_vec()
        })
    }

    /// An abscissa value (SI, or log10 SI) in the column's unit, for people.
    pub fn display(&self, x: f64, p_atm_pa: f64) -> f64 {
        let si = if self.log10 { 10f64.powf(x) } else { x };
        self.unit.from_si(si, p_atm_pa)
    }
}

/// The measured output channels of an experiment kind, in the simulator's order.
fn channels_of(kind: Kind) -> &'static [Quantity] {
    kind.model().channels()
}

/// The reference of one measured channel of one experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelReference {
    /// The experiment's kind.
    pub kind: Kind,
    /// Recording file name as given in rig.toml.
    pub file: String,
    /// The measured channel.
    pub quantity: Quantity,
    /// Column name as written in the file.
    pub column: String,
    /// The column's unit (for reports; the reference itself is SI).
    pub unit: Unit,
    /// What the channel is described against.
    pub abscissa: Abscissa,
    /// The fitted polynomial(s).
    pub reference: Reference,
}

impl ChannelReference {
    /// A value of this channel (SI) in the column's unit.
    pub fn display(&self, y: f64, p_atm_pa: f64) -> f64 {
        self.unit.from_si(y, p_atm_pa)
    }
    /// A difference of this channel (SI, e.g. σ) in the column's unit (no gauge offset).
    pub fn display_difference(&self, dy: f64, p_atm_pa: f64) -> f64 {
        self.unit.from_si(dy, p_atm_pa) - self.unit.from_si(0.0, p_atm_pa)
    }
}

/// The full scale of a stated (catalogue) channel of quantity `q` with values `ys`, SI, on
/// which its reading tolerance is taken: max|y|; for a torque printed only as the 0 at free
/// speed, the largest torque the page implies, power/speed of its rows (the torque at max
/// power is P_max/ω there). `None` where the page gives no magnitude at all: a reading
/// tolerance of 0 would make any deviation from the 0 infinitely unlikely, a cost that
/// cannot be evaluated.
fn stated_full_scale(q: Quantity, rec: &Recording, ys: &[f64]) -> Option<f64> {
    let ymax = ys.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    if ymax > 0.0 {
        return Some(ymax);
    }
    let implied = match (q, rec.values(Quantity::Power), rec.values(Quantity::Speed)) {
        (Quantity::Torque, Ok(p), Ok(w)) => p
            .iter()
            .zip(w)
            .filter(|(p, w)| p.is_finite() && **w > 0.0)
            .fold(0.0f64, |m, (p, w)| m.max((p / w).abs())),
        _ => 0.0,
    };
    (implied > 0.0).then_some(implied)
}

/// Why a stated channel has no full scale ([`stated_full_scale`]), with what to add: for a
/// page of figures only (its recording is rig.toml's) at the free speed's key, else at the
/// channel's column (`column_error`).
fn no_full_scale(
    data: &ExperimentData,
    q: Quantity,
    column: &str,
    column_error: impl Fn(String) -> DataError,
) -> DataError {
    if q != Quantity::Torque {
        return column_error(format!(
            "{column} is 0 in every row: no full scale to weigh its reading tolerance on; add a value other than 0"
        ));
    }
    let message = "the page prints no torque but the 0 at free speed, which says where the torque is 0 and not how large it is, so the fit has no scale to weigh it on: add the stall torque (stall_torque), the torque at max power (torque_at_max_power) or the max power with its speed (max_power, speed_at_max_power)".to_string();
    let rec = &data.recording;
    let free = data.figures.iter().find(|f| f.key == "free_speed");
    match free {
        Some(f) if rec.file.file_name().is_some_and(|n| n == "rig.toml") => DataError {
            file: rec.file.clone(),
            line: f.line,
            column: Some((1, f.key.clone())),
            named: crate::data::dataset::Named::Key,
            message,
        },
        _ => column_error(message),
    }
}

/// Fits the reference of every measured channel of an experiment. Errors name the file
/// and the channel's column.
pub fn experiment_references(
    data: &ExperimentData,
    options: &ReferenceOptions,
) -> Result<Vec<ChannelReference>, DataError> {
    let rec = &data.recording;
    let abscissa = Abscissa::of(data.kind, rec)?;
    let x = abscissa.measured(rec)?;
    let mut out = Vec::new();
    for &q in channels_of(data.kind) {
        let Some((i, col)) = rec
            .columns
            .iter()
            .enumerate()
            .find(|(_, c)| c.quantity == q)
        else {
            continue;
        };
        // A catalogue's empty cells (NaN) are not points of this channel.
        let (xs, ys): (Vec<f64>, Vec<f64>) = x
            .iter()
            .zip(&col.si)
            .filter(|(_, y)| y.is_finite())
            .map(|(x, y)| (*x, *y))
            .unzip();
        if ys.is_empty() {
            continue;
        }
        let column_error = |message: String| {
            let mut err = DataError::new(&rec.file, message);
            err.column = Some((i + 1, col.name.clone()));
            err
        };
        let fitted = match data.tolerance {
            None => Reference::fit(&xs, &ys, options),
            Some(tol) => {
                let scale = stated_full_scale(q, rec, &ys)
                    .ok_or_else(|| no_full_scale(data, q, &col.name, column_error))?;
                Reference::stated(&xs, &ys, options, tol, scale)
            }
        };
        let reference = fitted.map_err(|e| {
            column_error(format!(
                "no reference response against {}: {e}",
                abscissa.column
            ))
        })?;
        out.push(ChannelReference {
            kind: data.kind,
            file: data.file.clone(),
            quantity: q,
            column: col.name.clone(),
            unit: col.unit,
            abscissa: abscissa.clone(),
            reference,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};
    use rand_xoshiro::Xoshiro256PlusPlus;

    fn noise(n: usize, sd: f64, seed: u64) -> Vec<f64> {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        let d = Normal::new(0.0, sd).unwrap();
        (0..n).map(|_| d.sample(&mut rng)).collect()
    }

    fn linspace(a: f64, b: f64, n: usize) -> Vec<f64> {
        (0..n)
            .map(|k| a + (b - a) * k as f64 / (n - 1) as f64)
            .collect()
    }

    #[test]
    fn known_polynomial_is_recovered_exactly() {
        // y = 2 − 3x + 0.5x³ on a badly scaled abscissa (x in Pa around 5e5).
        let x = linspace(1e5, 7.3e5, 37);
        let f = |x: f64| {
            let s = x / 1e5;
            2.0 - 3.0 * s + 0.5 * s.powi(3)
        };
        let y: Vec<f64> = x.iter().map(|v| f(*v)).collect();
        let piece = Piece::fit(&x, &y, 3).unwrap();
        for xi in linspace(1e5, 7.3e5, 101) {
            assert!((piece.value(xi) - f(xi)).abs() < 1e-9, "at {xi}");
        }
        assert!(piece.rss < 1e-20);
        let r = Reference::fit(&x, &y, &ReferenceOptions::default()).unwrap();
        assert_eq!(r.degree(), 3);
        assert_eq!(r.pieces().len(), 1);
        assert!((r.eval(4e5).unwrap() - f(4e5)).abs() < 1e-9);
        assert!(r.r_squared() > 1.0 - 1e-12);
        assert_eq!(r.range(), (1e5, 7.3e5));
        assert_eq!(r.eval(0.99e5), None);
        assert_eq!(r.eval(7.31e5), None);
    }

    #[test]
    fn degree_selection_finds_the_true_degree_and_sigma_the_noise() {
        // Torque-like curve, degree 2, noise 2 mN·m, 200 points; several seeds.
        let x = linspace(0.0, 1270.0, 200);
        let f = |w: f64| 0.31 - 1.8e-4 * w - 9e-8 * w * w;
        for seed in 1..=5 {
            let e = noise(x.len(), 2e-3, seed);
            let y: Vec<f64> = x.iter().zip(&e).map(|(w, e)| f(*w) + e).collect();
            let r = Reference::fit(&x, &y, &ReferenceOptions::default()).unwrap();
            assert_eq!(r.degree(), 2, "seed {seed}");
            assert_eq!(r.pieces().len(), 1, "seed {seed}");
            let s = r.sigma();
            assert!((s / 2e-3 - 1.0).abs() < 0.15, "seed {seed}: σ = {s}");
        }
        // Cubic with a clear x³ term on a log abscissa.
        let x = linspace(-8.8, -7.5, 150);
        let g = |u: f64| 1.9 + 0.8 * (u + 8.0) - 0.5 * (u + 8.0).powi(2) + 0.9 * (u + 8.0).powi(3);
        let e = noise(x.len(), 0.01, 42);
        let y: Vec<f64> = x.iter().zip(&e).map(|(u, e)| g(*u) + e).collect();
        let r = Reference::fit(&x, &y, &ReferenceOptions::default()).unwrap();
        assert_eq!(r.degree(), 3);
        assert!((r.sigma() / 0.01 - 1.0).abs() < 0.15, "σ = {}", r.sigma());
    }

    #[test]
    fn degree_is_capped_below_a_third_of_the_points() {
        let x = linspace(0.0, 1.0, 10);
        let y: Vec<f64> = x.iter().map(|v| (6.0 * v).sin()).collect();
        let r = Reference::fit(&x, &y, &ReferenceOptions::default()).unwrap();
        assert!(r.degree() <= 3);
        assert!(Reference::fit(&x[..3], &y[..3], &ReferenceOptions::default()).is_err());
        assert!(Reference::fit(
            &[1.0; 5],
            &[1.0, 2.0, 3.0, 4.0, 5.0],
            &ReferenceOptions::default()
        )
        .is_err());
    }

    /// Speed after breakaway, rad/s, against port-1 pressure, Pa.
    fn breakaway_curve(p: f64) -> f64 {
        let s = (p - 2.0e5) / 5.3e5;
        300.0 + 900.0 * s - 400.0 * s * s
    }

    /// A pressure ramp with breakaway: speed ≈ 0 until 0.2 MPa, then jumps to 300 rad/s
    /// and rises; a few points in between while the rotor accelerates.
    fn step_ramp(seed: u64) -> (Vec<f64>, Vec<f64>) {
        let n = 600;
        let p = linspace(1.0e5, 7.3e5, n);
        let px = noise(n, 1e3, seed);
        let ey = noise(n, 0.5, seed + 100);
        let mut x = Vec::new();
        let mut y = Vec::new();
        for i in 0..n {
            let pi = p[i];
            let w = if pi < 2.0e5 {
                0.0
            } else if pi < 2.04e5 {
                // rotor accelerating
                300.0 * (pi - 2.0e5) / 4e3
            } else {
                breakaway_curve(pi)
            };
            x.push(pi + px[i]);
            y.push(w + ey[i]);
        }
        (x, y)
    }

    #[test]
    fn jump_is_split_not_smeared() {
        let (x, y) = step_ramp(3);
        let r = Reference::fit(&x, &y, &ReferenceOptions::default()).unwrap();
        assert!(r.pieces().len() >= 2, "{:?}", r.pieces().len());
        let first = &r.pieces()[0];
        // The standstill piece ends at the breakaway.
        assert!(
            (first.x_max - 2.0e5).abs() < 6e3,
            "split at {} Pa",
            first.x_max
        );
        // Standing still below, at speed above, no overshoot into the jump.
        assert!(r.eval(1.5e5).unwrap().abs() < 1.0);
        assert!(r.eval(1.95e5).unwrap().abs() < 1.5);
        let above = r.eval(2.1e5).unwrap();
        let truth = breakaway_curve(2.1e5);
        assert!((above - truth).abs() < 1.0, "{above} vs {truth}");
        // Noise estimated from both pieces, not inflated by the jump. It includes the
        // pressure sensor's 1 kPa noise seen through the slope dω/dp after breakaway:
        // σ² = 0.5² + (1e3·dω/dp)², pooled over the pieces, ≈ 1.08² (rad/s)².
        assert!((r.sigma() / 1.08 - 1.0).abs() < 0.1, "σ = {}", r.sigma());
        // Inside the jump there is no reference: a gap around 2.0–2.04 bar (narrower or
        // shifted by the pressure sensor's noise).
        let (gap_lo, gap_hi) = (r.pieces()[0].x_max, r.pieces()[1].x_min);
        assert!(gap_lo < gap_hi, "no gap");
        assert!(gap_lo > 1.95e5 && gap_hi < 2.1e5, "gap {gap_lo}..{gap_hi}");
        assert_eq!(r.eval(0.5 * (gap_lo + gap_hi)), None);
    }

    #[test]
    fn smooth_data_are_not_split() {
        for seed in 1..=4 {
            let x = linspace(1.0e5, 7.3e5, 600);
            let e = noise(x.len(), 1e-5, seed);
            let y: Vec<f64> = x
                .iter()
                .zip(&e)
                .map(|(p, e)| 7e-9 * p - 1e-15 * p * p + e)
                .collect();
            let r = Reference::fit(&x, &y, &ReferenceOptions::default()).unwrap();
            assert_eq!(r.pieces().len(), 1, "seed {seed}");
        }
    }

    #[test]
    fn sigma_never_falls_below_the_resolution_floor() {
        let x = linspace(0.0, 10.0, 20);
        let y: Vec<f64> = x.iter().map(|v| 3.0 + 0.5 * v).collect();
        let r = Reference::fit(&x, &y, &ReferenceOptions::default()).unwrap();
        assert!(r.sigma_residual() < 1e-12);
        assert!((r.sigma() - 8.0 / 4096.0).abs() < 1e-15);
    }
}
