//! Input schedules: a recorded input column (supply pressure, port-2 conductance) turned into
//! a smooth function of time that drives a transient simulation.
//!
//! Recorded inputs carry sensor noise, while the pressure a regulator applies is smooth. Fed
//! to the integrator raw, every noisy sample would be a kink that forces small steps. So the
//! samples are averaged in bins (at most `MAX_KNOTS` of them) and joined by a monotone cubic
//! (PCHIP, Fritsch–Carlson), which is C¹, never overshoots, and reproduces a linear ramp
//! exactly. Outside the knots it extends linearly.

/// Upper bound on the knots of a schedule. The reference experiments are slow ramps
/// (docs/model.md, "Reference experiments"): 16 knots follow any input that changes over
/// more than a sixteenth of the record, and each knot averages ~40 samples of a 10 Hz, 60 s
/// record, so 1 kPa of sensor noise leaves ≈0.15 kPa. Measured on the shipped dataset: one
/// cost evaluation took 1.76 ms with 64 knots, 1.01 ms with 32 and 0.76 ms with 16 (noisy
/// knots make the integrator follow wiggles that are not in the applied input).
const MAX_KNOTS: usize = 16;

/// One segment of a [`Schedule`]: the cubic v + τ·(slope + τ·(c2 + τ·c3)) in τ = time − t
/// from its left knot.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Piece {
    /// The left knot's time, s.
    t: f64,
    /// The value at the left knot.
    v: f64,
    /// The slope at the left knot, per second.
    slope: f64,
    /// The coefficients of τ² and τ³.
    c2: f64,
    c3: f64,
}

/// A C¹ monotone-cubic function of time.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Schedule {
    t: Vec<f64>,
    v: Vec<f64>,
    slope: Vec<f64>,
    /// Per segment k, the cubic in τ = time − t_k: v_k + τ·(s_k + τ·(c2_k + τ·c3_k)).
    /// Computed once: the integrator asks for the input at every evaluation of the
    /// right-hand side, and Horner's form there is a handful of multiply-adds. Each segment's
    /// five numbers sit together (one bounds check and one cache line per lookup instead of
    /// four of each: the lookups were ~5 % of an evaluation's instructions).
    pieces: Vec<Piece>,
    /// Knots per second, (n − 1)/(t_last − t_first): bin means of evenly sampled rows are
    /// nearly evenly spaced, so the segment of a time is found from this guess in a step
    /// or two instead of a binary search (the integrator asks at every right-hand side).
    knots_per_s: f64,
}

impl Schedule {
    /// Bin-averages `values` sampled at increasing `times` and interpolates the bin means.
    pub fn smoothed(times: &[f64], values: &[f64]) -> Self {
        let n = times.len().min(values.len());
        let per_bin = n.div_ceil(MAX_KNOTS).max(1);
        let mut t = Vec::with_capacity(MAX_KNOTS);
        let mut v = Vec::with_capacity(MAX_KNOTS);
        for start in (0..n).step_by(per_bin) {
            let end = (start + per_bin).min(n);
            let k = (end - start) as f64;
            t.push(times[start..end].iter().sum::<f64>() / k);
            v.push(values[start..end].iter().sum::<f64>() / k);
        }
        Self::through(t, v)
    }

    /// The monotone cubic through the given knots (times increasing).
    pub fn through(t: Vec<f64>, v: Vec<f64>) -> Self {
        let slope = pchip_slopes(&t, &v);
        let pieces = (1..t.len())
            .map(|k| {
                // Hermite cubic through (t, v, slope) at both ends, in powers of τ.
                let h = t[k] - t[k - 1];
                let secant = (v[k] - v[k - 1]) / h;
                let (s0, s1) = (slope[k - 1], slope[k]);
                Piece {
                    t: t[k - 1],
                    v: v[k - 1],
                    slope: s0,
                    c2: (3.0 * secant - 2.0 * s0 - s1) / h,
                    c3: (s0 + s1 - 2.0 * secant) / (h * h),
                }
            })
            .collect();
        let n = t.len();
        let knots_per_s = if n > 1 {
            (n - 1) as f64 / (t[n - 1] - t[0])
        } else {
            0.0
        };
        Self {
            t,
            v,
            slope,
            pieces,
            knots_per_s,
        }
    }

    /// A constant schedule.
    pub fn constant(value: f64) -> Self {
        Self::through(vec![0.0], vec![value])
    }

    /// Value at time `time`.
    pub fn at(&self, time: f64) -> f64 {
        let n = self.t.len();
        if n == 1 {
            return self.v[0];
        }
        if time <= self.t[0] {
            return self.v[0] + self.slope[0] * (time - self.t[0]);
        }
        if time >= self.t[n - 1] {
            return self.v[n - 1] + self.slope[n - 1] * (time - self.t[n - 1]);
        }
        let Piece {
            t,
            v,
            slope,
            c2,
            c3,
        } = self.pieces[self.segment(time)];
        let tau = time - t;
        v + tau * (slope + tau * (c2 + tau * c3))
    }

    /// Time derivative at `time`, per second: the cubic's slope inside the knots, the end
    /// slopes outside (as [`Schedule::at`] extends), 0 for a constant.
    pub(crate) fn slope_at(&self, time: f64) -> f64 {
        let n = self.t.len();
        if n == 1 {
            return 0.0;
        }
        if time <= self.t[0] {
            return self.slope[0];
        }
        if time >= self.t[n - 1] {
            return self.slope[n - 1];
        }
        let Piece {
            t, slope, c2, c3, ..
        } = self.pieces[self.segment(time)];
        let tau = time - t;
        slope + tau * (2.0 * c2 + tau * 3.0 * c3)
    }

    /// The last knot k with t_k ≤ `time`, for t_0 < time < t_last: a guess from the mean
    /// knot spacing, corrected by walking to the right segment.
    fn segment(&self, time: f64) -> usize {
        let last = self.t.len() - 2;
        // `as` saturates: NaN and negative guesses become 0.
        let mut k = (((time - self.t[0]) * self.knots_per_s) as usize).min(last);
        while k > 0 && self.t[k] > time {
            k -= 1;
        }
        while k < last && self.t[k + 1] <= time {
            k += 1;
        }
        k
    }
}

/// Fritsch–Carlson slopes: harmonic mean of neighbouring secants, zero at extrema.
fn pchip_slopes(t: &[f64], v: &[f64]) -> Vec<f64> {
    let n = t.len();
    if n < 2 {
        return vec![0.0; n];
    }
    let secant: Vec<f64> = (0..n - 1)
        .map(|k| (v[k + 1] - v[k]) / (t[k + 1] - t[k]))
        .collect();
    let mut slope = vec![0.0; n];
    slope[0] = secant[0];
    slope[n - 1] = secant[n - 2];
    for k in 1..n - 1 {
        let (a, b) = (secant[k - 1], secant[k]);
        if a * b > 0.0 {
            let (h0, h1) = (t[k] - t[k - 1], t[k + 1] - t[k]);
            let (w1, w2) = (2.0 * h1 + h0, h1 + 2.0 * h0);
            slope[k] = (w1 + w2) / (w1 / a + w2 / b);
        }
    }
    slope
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_ramp_is_reproduced_exactly() {
        let times: Vec<f64> = (0..601).map(|k| f64::from(k) * 0.1).collect();
        let values: Vec<f64> = times.iter().map(|t| 1e5 + 1e4 * t).collect();
        let s = Schedule::smoothed(&times, &values);
        for t in [0.0, 0.05, 13.37, 59.99, 60.0] {
            assert!((s.at(t) - (1e5 + 1e4 * t)).abs() < 1e-6, "t = {t}");
        }
    }

    #[test]
    fn cubic_pieces_are_the_hermite_interpolant() {
        // Independent re-computation with the Hermite basis: values and slopes at knots.
        let t = vec![0.0, 1.0, 2.5, 4.0];
        let v = vec![1.0, 3.0, 3.5, 7.0];
        let s = Schedule::through(t.clone(), v.clone());
        for k in 0..3 {
            let h = t[k + 1] - t[k];
            for x in [0.1, 0.5, 0.9] {
                let (h00, h10, h01, h11) = (
                    (1.0 + 2.0 * x) * (1.0 - x) * (1.0 - x),
                    x * (1.0 - x) * (1.0 - x),
                    x * x * (3.0 - 2.0 * x),
                    x * x * (x - 1.0),
                );
                let hermite =
                    h00 * v[k] + h10 * h * s.slope[k] + h01 * v[k + 1] + h11 * h * s.slope[k + 1];
                assert!((s.at(t[k] + x * h) - hermite).abs() < 1e-12);
            }
        }
    }

    #[test]
    fn slope_is_the_derivative_of_the_value() {
        let t = vec![0.0, 1.0, 2.5, 4.0];
        let v = vec![1.0, 3.0, 3.5, 7.0];
        let s = Schedule::through(t, v);
        for time in [-0.5, 0.3, 1.7, 2.5, 3.9, 4.5] {
            let h = 1e-6;
            let fd = (s.at(time + h) - s.at(time - h)) / (2.0 * h);
            // At a knot (t = 2.5) the difference straddles two cubics: C¹, so it agrees to
            // O(h·jump of the second derivative).
            assert!((s.slope_at(time) - fd).abs() < 1e-5, "t = {time}");
        }
        assert_eq!(Schedule::constant(3.0).slope_at(1.0), 0.0);
    }

    #[test]
    fn segment_guess_agrees_with_a_binary_search() {
        // Uneven knots, so that the guess from the mean spacing is often wrong.
        let t = vec![0.0, 0.1, 0.15, 2.0, 2.05, 7.0, 7.5, 9.0, 12.0];
        let v: Vec<f64> = t.iter().map(|x| x * x).collect();
        let s = Schedule::through(t.clone(), v);
        for k in 1..12_000 {
            let time = f64::from(k) * 1e-3;
            let want = t.partition_point(|tk| *tk <= time) - 1;
            assert_eq!(s.segment(time), want, "t = {time}");
        }
        for &time in &t[1..t.len() - 1] {
            assert_eq!(s.segment(time), t.partition_point(|tk| *tk <= time) - 1);
        }
    }

    #[test]
    fn monotone_data_give_a_monotone_schedule() {
        let t: Vec<f64> = (0..10).map(f64::from).collect();
        let v = vec![0.0, 0.0, 1.0, 5.0, 5.1, 5.1, 9.0, 9.0, 9.5, 12.0];
        let s = Schedule::through(t, v);
        let mut last = f64::NEG_INFINITY;
        for k in 0..=900 {
            let y = s.at(f64::from(k) * 0.01);
            assert!(y >= last - 1e-12);
            last = y;
        }
    }
}
