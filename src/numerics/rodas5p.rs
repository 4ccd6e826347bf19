//! Rodas5P (Steinebach 2023): a stiffly accurate, L-stable Rosenbrock method of order 5
//! with an embedded order-4 estimate and an order-4 dense output, eight stages. A trial
//! against Rodas4 (the same driver, kink landings and controller, err^(−1/5)).
//! Coefficients as tabulated in OrdinaryDiffEq.jl's `Rodas5PTableau`.

use super::lu::Lu;
use super::ode::{
    Jacobian, Kinks, Rhs, SolveError, State, StiffSolver, Tolerances, N_KINKS, N_STATES,
};
use super::rodas::Linearisation;

const GAMMA: f64 = 0.21193756319429014;
const C: [f64; 5] = [
    0.0,
    0.6358126895828704,
    0.4095798393397535,
    0.9769306725060716,
    0.4288403609558664,
];
const D: [f64; 5] = [
    0.21193756319429014,
    -0.42387512638858027,
    -0.3384627126235924,
    1.8046452872882734,
    2.325825639765069,
];
const A: [[f64; 5]; 5] = [
    [3.0, 0.0, 0.0, 0.0, 0.0],
    [2.849394379747939, 0.45842242204463923, 0.0, 0.0, 0.0],
    [
        -6.954028509809101,
        2.489845061869568,
        -10.358996098473584,
        0.0,
        0.0,
    ],
    [
        2.8029986275628964,
        0.5072464736228206,
        -0.3988312541770524,
        -0.04721187230404641,
        0.0,
    ],
    [
        -7.502846399306121,
        2.561846144803919,
        -11.627539656261098,
        -0.18268767659942256,
        0.030198172008377946,
    ],
];
const CC: [[f64; 7]; 7] = [
    [-14.155112264123755, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
    [
        -17.97296035885952,
        -2.859693295451294,
        0.0,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        147.12150275711716,
        -1.41221402718213,
        71.68940251302358,
        0.0,
        0.0,
        0.0,
        0.0,
    ],
    [
        165.43517024871676,
        -0.4592823456491126,
        42.90938336958603,
        -5.961986721573306,
        0.0,
        0.0,
        0.0,
    ],
    [
        24.854864614690072,
        -3.0009227002832186,
        47.4931110020768,
        5.5814197821558125,
        -0.6610691825249471,
        0.0,
        0.0,
    ],
    [
        30.91273214028599,
        -3.1208243349937974,
        77.79954646070892,
        34.28646028294783,
        -19.097331116725623,
        -28.087943162872662,
        0.0,
    ],
    [
        37.80277123390563,
        -3.2571969029072276,
        112.26918849496327,
        66.9347231244047,
        -40.06618937091002,
        -54.66780262877968,
        -9.48861652309627,
    ],
];
const H: [[f64; 8]; 3] = [
    [
        25.948786856663858,
        -2.5579724845846235,
        10.433815404888879,
        -2.3679251022685204,
        0.524948541321073,
        1.1241088310450404,
        0.4272876194431874,
        -0.17202221070155493,
    ],
    [
        -9.91568850695171,
        -0.9689944594115154,
        3.0438037242978453,
        -24.495224566215796,
        20.176138334709044,
        15.98066361424651,
        -6.789040303419874,
        -6.710236069923372,
    ],
    [
        11.419903575922262,
        2.8879645146136994,
        72.92137995996029,
        80.12511834622643,
        -52.072871366152654,
        -59.78993625266729,
        -0.15582684282751913,
        4.883087185713722,
    ],
];

const MAX_STEPS: usize = 200_000;

/// Rodas5P with adaptive steps (a trial; see the module documentation).
#[derive(Debug, Clone, Copy)]
pub struct Rodas5P {
    /// Integration tolerances.
    pub tol: Tolerances,
}

impl Default for Rodas5P {
    fn default() -> Self {
        Self {
            tol: super::rodas::Rodas4::default().tol,
        }
    }
}

/// One step's result.
#[derive(Debug, Clone, Copy)]
pub struct Step {
    pub y1: State,
    pub err: State,
    dense: [State; 3],
}

impl Step {
    fn interpolate(&self, y0: &State, theta: f64) -> State {
        let [g1, g2, g3] = &self.dense;
        std::array::from_fn(|i| {
            (1.0 - theta) * y0[i]
                + theta * (self.y1[i] + (1.0 - theta) * (g1[i] + theta * (g2[i] + theta * g3[i])))
        })
    }
}

fn combine<const S: usize>(coef: &[f64], k: &[State; 8]) -> State {
    std::array::from_fn(|i| {
        let mut sum = coef[0] * k[0][i];
        for j in 1..S {
            sum += coef[j] * k[j][i];
        }
        sum
    })
}

/// One Rodas5P step.
pub fn step(rhs: &Rhs<'_>, t: f64, y: &State, lin: &Linearisation, h: f64) -> Option<Step> {
    let mut w = [[0.0; N_STATES]; N_STATES];
    for (i, row) in w.iter_mut().enumerate() {
        for (j, wij) in row.iter_mut().enumerate() {
            *wij = f64::from(u8::from(i == j)) / (GAMMA * h) - lin.jac[i][j];
        }
    }
    let lu = Lu::new(w)?;
    let inv_h = 1.0 / h;
    let mut k = [[0.0; N_STATES]; 8];
    k[0] = lu.solve(std::array::from_fn(|i| lin.f[i] + D[0] * h * lin.f_t[i]));
    let stage = |arg: &State, c: f64, d: f64, couplings: State| -> State {
        let f = rhs(t + c * h, arg);
        lu.solve(std::array::from_fn(|i| {
            f[i] + d * h * lin.f_t[i] + inv_h * couplings[i]
        }))
    };
    let shifted = |sum: State| -> State { std::array::from_fn(|i| y[i] + sum[i]) };
    k[1] = stage(
        &shifted(combine::<1>(&A[0], &k)),
        C[1],
        D[1],
        combine::<1>(&CC[0], &k),
    );
    k[2] = stage(
        &shifted(combine::<2>(&A[1], &k)),
        C[2],
        D[2],
        combine::<2>(&CC[1], &k),
    );
    k[3] = stage(
        &shifted(combine::<3>(&A[2], &k)),
        C[3],
        D[3],
        combine::<3>(&CC[2], &k),
    );
    k[4] = stage(
        &shifted(combine::<4>(&A[3], &k)),
        C[4],
        D[4],
        combine::<4>(&CC[3], &k),
    );
    let arg6 = shifted(combine::<5>(&A[4], &k));
    k[5] = stage(&arg6, 1.0, 0.0, combine::<5>(&CC[4], &k));
    let arg7: State = std::array::from_fn(|i| arg6[i] + k[5][i]);
    k[6] = stage(&arg7, 1.0, 0.0, combine::<6>(&CC[5], &k));
    let arg8: State = std::array::from_fn(|i| arg7[i] + k[6][i]);
    k[7] = stage(&arg8, 1.0, 0.0, combine::<7>(&CC[6], &k));
    let y1: State = std::array::from_fn(|i| arg8[i] + k[7][i]);
    let dense = [
        combine::<8>(&H[0], &k),
        combine::<8>(&H[1], &k),
        combine::<8>(&H[2], &k),
    ];
    Some(Step {
        y1,
        err: k[7],
        dense,
    })
}

/// How far past a kink's estimated position a landing step ends, as a fraction of the
/// rejected step: enough that the estimate's error rarely leaves the kink ahead of the
/// landing, small enough that the stretch beyond it adds little error.
const KINK_OVERSHOOT: f64 = 0.01;

/// Where in a rejected step of size `h` the first kink lies, as a fraction of the step, for
/// the indicators that change sign between its start (`g_start`, changing at `g_rate` per
/// second along the solution there) and its end (`g_end`): from the start's tangent where
/// that reaches zero inside the step (the end of a rejected step is the least reliable
/// point near a kink), else by linear interpolation between the ends. `None` when no
/// indicator changes sign.
fn kink_fraction(
    g_start: &[f64; N_KINKS],
    g_rate: &[f64; N_KINKS],
    g_end: &[f64; N_KINKS],
    h: f64,
) -> Option<f64> {
    (0..N_KINKS)
        .filter(|&i| (g_start[i] > 0.0) != (g_end[i] > 0.0))
        .map(|i| {
            let tangent = -g_start[i] / (g_rate[i] * h);
            if tangent > 0.0 && tangent <= 1.0 {
                tangent
            } else {
                g_start[i] / (g_start[i] - g_end[i])
            }
        })
        .filter(|theta| theta.is_finite())
        .min_by(f64::total_cmp)
}

/// Step-size control of Hairer & Wanner's RODAS: the classical h·err^(−1/4) rule combined
/// with Gustafsson's predictive controller, which uses the previous accepted step as well
/// and so rejects fewer steps where the error changes steadily (a ramp). Factors: at most
/// ×6 up, ×0.2 down, safety 0.9; no growth right after a rejection.
#[derive(Debug, Clone, Copy, Default)]
struct StepControl {
    /// The last accepted step and its error (0 before the first).
    previous: Option<(f64, f64)>,
    /// Whether the last attempt was rejected.
    after_reject: bool,
}

impl StepControl {
    const SAFETY: f64 = 0.9;
    const MAX_GROWTH: f64 = 6.0;
    const MAX_SHRINK: f64 = 0.2;

    /// The next step after an accepted step h with error norm err ≤ 1.
    fn accepted(&mut self, h: f64, err: f64) -> f64 {
        let err = err.max(1e-10);
        let mut fac = (Self::SAFETY / fifth_root(err)).clamp(Self::MAX_SHRINK, Self::MAX_GROWTH);
        if let Some((h_prev, err_prev)) = self.previous {
            let predicted = Self::SAFETY * (h / h_prev) * fifth_root(err_prev / (err * err));
            fac = fac.min(predicted.clamp(Self::MAX_SHRINK, Self::MAX_GROWTH));
        }
        if self.after_reject {
            fac = fac.min(1.0);
        }
        self.previous = Some((h, err.max(1e-2)));
        self.after_reject = false;
        h * fac
    }

    /// The retry after a rejected step h (err > 1, infinite when the step failed).
    fn rejected(&mut self, h: f64, err: f64) -> f64 {
        self.after_reject = true;
        let fac = if err.is_finite() {
            (Self::SAFETY / fifth_root(err)).clamp(Self::MAX_SHRINK, Self::SAFETY)
        } else {
            0.25
        };
        h * fac
    }
}

/// x^(1/4) as two square roots: the step control asks for it after every step, and `powf`
/// cost ~2 % of an evaluation's instructions.
fn fifth_root(x: f64) -> f64 {
    x.powf(0.2)
}

impl Rodas5P {
    /// RMS of the error estimate scaled by atol_i + rtol·max(|y0_i|, |y1_i|).
    fn error_norm(&self, y0: &State, s: &Step) -> f64 {
        let size: State = std::array::from_fn(|i| y0[i].abs().max(s.y1[i].abs()));
        self.weighted_rms(&s.err, &size)
    }

    /// RMS of v_i / (atol_i + rtol·size_i): the norm every step decision is made in.
    fn weighted_rms(&self, v: &State, size: &State) -> f64 {
        let sum: f64 = (0..N_STATES)
            .map(|i| (v[i] / (self.tol.atol[i] + self.tol.rtol * size[i])).powi(2))
            .sum();
        (sum / N_STATES as f64).sqrt()
    }

    /// A first step from the size of f and of its change along an Euler step (Hairer &
    /// Wanner's `hinit`, order 4), at most the whole interval.
    fn initial_step(&self, rhs: &Rhs<'_>, t0: f64, y0: &State, f0: &State, span: f64) -> f64 {
        let size = y0.map(f64::abs);
        let norm = |v: &State| self.weighted_rms(v, &size);
        let (d0, d1) = (norm(y0), norm(f0));
        let h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        }
        .min(span);
        let y1: State = std::array::from_fn(|i| y0[i] + h0 * f0[i]);
        let f1 = rhs(t0 + h0, &y1);
        let df: State = std::array::from_fn(|i| f1[i] - f0[i]);
        let d2 = norm(&df) / h0;
        let h1 = if d1.max(d2) <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            (0.01 / d1.max(d2)).powf(0.2)
        };
        (100.0 * h0).min(h1).min(span)
    }
}

impl StiffSolver for Rodas5P {
    fn solve(
        &self,
        rhs: &Rhs<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        self.solve_with_jacobian(rhs, &|_, _| None, t0, x0, t_out)
    }

    fn solve_with_jacobian(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        self.solve_with_kinks(rhs, jacobian, &|_, _| [1.0; N_KINKS], t0, x0, t_out)
    }

    fn solve_with_kinks(
        &self,
        rhs: &Rhs<'_>,
        jacobian: &Jacobian<'_>,
        kinks: &Kinks<'_>,
        t0: f64,
        x0: State,
        t_out: &[f64],
    ) -> Result<Vec<State>, SolveError> {
        let mut out = Vec::with_capacity(t_out.len());
        let Some(&t_end) = t_out.last() else {
            return Ok(out);
        };
        if t_out.windows(2).any(|w| w[1] < w[0]) || t_out[0] < t0 {
            return Err(SolveError("output times must increase from t0".into()));
        }
        let (mut t, mut y) = (t0, x0);
        let mut k = 0;
        while k < t_out.len() && t_out[k] <= t {
            out.push(y);
            k += 1;
        }
        if k == t_out.len() {
            return Ok(out);
        }
        let mut lin = Linearisation::at(rhs, jacobian, t, &y);
        let mut h = self.initial_step(rhs, t, &y, &lin.f, t_end - t0);
        let mut control = StepControl::default();
        // The kink indicators at the current point (computed when a step is rejected), and
        // the step to resume with after landing just past a kink.
        let mut g0: Option<([f64; N_KINKS], [f64; N_KINKS])> = None;
        let mut resume: Option<f64> = None;
        for _ in 0..MAX_STEPS {
            // Land exactly on t_end; stretch a step that would leave a sliver before it.
            let remaining = t_end - t;
            let last = h >= remaining * (1.0 - 1e-12) || remaining - h < 1e-3 * h;
            let h_try = if last { remaining } else { h };
            let step = step(rhs, t, &y, &lin, h_try);
            let err = step.map_or(f64::INFINITY, |s| self.error_norm(&y, &s));
            let (Some(s), true) = (step, err <= 1.0) else {
                // Rejected: if the trial crossed a kink, retry with a step that ends just past
                // it (the part after the kink is then too short to matter, and the next step
                // starts on the kink's far side); else shrink as the controller says. Either
                // way from the same point (J and ∂f/∂t still hold).
                let landing = step.and_then(|s| {
                    let (g_start, g_rate) = *g0.get_or_insert_with(|| {
                        let g = kinks(t, &y);
                        // Each indicator's rate along the solution, per second.
                        let d = 1e-6 * t.abs().max(1.0);
                        let ahead = kinks(t + d, &std::array::from_fn(|i| y[i] + d * lin.f[i]));
                        (g, std::array::from_fn(|i| (ahead[i] - g[i]) / d))
                    });
                    kink_fraction(&g_start, &g_rate, &kinks(t + h_try, &s.y1), h_try)
                });
                h = match landing {
                    Some(theta) if resume.is_none() => {
                        resume = Some(h_try);
                        h_try * (theta + KINK_OVERSHOOT).min(1.0)
                    }
                    _ => control.rejected(h_try, err),
                };
                if h < 1e-14 * t.abs().max(1.0) {
                    return Err(SolveError(format!("step size underflow at t = {t} s")));
                }
                continue;
            };
            let t_new = if last { t_end } else { t + h_try };
            while k < t_out.len() && t_out[k] <= t_new {
                let theta = ((t_out[k] - t) / h_try).clamp(0.0, 1.0);
                out.push(if t_out[k] == t_new {
                    s.y1
                } else {
                    s.interpolate(&y, theta)
                });
                k += 1;
            }
            if k == t_out.len() {
                return Ok(out);
            }
            t = t_new;
            y = s.y1;
            lin = Linearisation::at(rhs, jacobian, t, &y);
            g0 = None;
            h = control.accepted(h_try, err);
            if let Some(h_before) = resume.take() {
                // Past the kink the solution is smooth again at the scale it had before it:
                // back to that step, but by no more than the controller's largest growth
                // from the landing step (a full return let errors past the estimate through:
                // 0.014σ on the shipped dataset instead of 0.0015σ).
                h = h.max(h_before.min(StepControl::MAX_GROWTH * h_try));
            }
        }
        Err(SolveError(format!(
            "more than {MAX_STEPS} steps before t = {t_end} s (stopped at t = {t} s)"
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pr(t: f64, x: &State) -> State {
        [
            -1e4 * (x[0] - t.sin()) + t.cos(),
            -x[1] + t.cos(),
            x[3],
            -x[2],
        ]
    }

    fn exact(t: f64) -> State {
        [
            t.sin(),
            0.5 * (t.sin() + t.cos()) + 0.5 * (-t).exp(),
            t.cos(),
            -t.sin(),
        ]
    }

    fn fixed_steps(n: usize) -> f64 {
        let (mut t, mut y) = (0.0, exact(0.0));
        let h = 1.0 / n as f64;
        for _ in 0..n {
            let lin = Linearisation::at(&pr, &|_, _| None, t, &y);
            y = step(&pr, t, &y, &lin, h).unwrap().y1;
            t += h;
        }
        let e = exact(1.0);
        (1..4).map(|i| (y[i] - e[i]).abs()).fold(0.0, f64::max)
    }

    #[test]
    fn order_five_on_smooth_problems() {
        let (e1, e2) = (fixed_steps(10), fixed_steps(20));
        let order = (e1 / e2).log2();
        assert!(
            (4.6..5.6).contains(&order),
            "observed order {order} ({e1}, {e2})"
        );
    }

    #[test]
    fn dense_output_order() {
        let err = |h: f64| {
            let y0 = exact(1.0);
            let lin = Linearisation::at(&pr, &|_, _| None, 1.0, &y0);
            let s = step(&pr, 1.0, &y0, &lin, h).unwrap();
            let mid = s.interpolate(&y0, 0.37);
            let e = exact(1.0 + 0.37 * h);
            (1..4).map(|i| (mid[i] - e[i]).abs()).fold(0.0, f64::max)
        };
        let order = (err(0.2) / err(0.1)).log2();
        assert!(order > 4.5, "dense-output local order {order}");
    }
}
