//! Finite differences: the one Hessian (curvature-shaped restarts of the optimizer, the
//! covariance of the estimate) and the one central-difference Jacobian column (the
//! sensitivities a diagnosis regresses on).

use nalgebra::DMatrix;

/// Hessian of `f` at `x` by central differences of step `h`, given f0 = f(x):
/// H_ii = (f(x+h·e_i) − 2·f0 + f(x−h·e_i))/h², and for i ≠ j
/// H_ij = (f(x+h·e_i+h·e_j) − f(x+h·e_i−h·e_j) − f(x−h·e_i+h·e_j) + f(x−h·e_i−h·e_j))/(4h²).
/// The diagonal steps are taken first, then the mixed ones row by row (2k + 2k(k−1)
/// evaluations); f0 is passed in because every caller already has it.
pub(crate) fn hessian(f: &dyn Fn(&[f64]) -> f64, x: &[f64], f0: f64, h: f64) -> DMatrix<f64> {
    let k = x.len();
    let at = |moves: &[(usize, f64)]| {
        let mut t = x.to_vec();
        for (i, d) in moves {
            t[*i] += d;
        }
        f(&t)
    };
    let mut hess = DMatrix::<f64>::zeros(k, k);
    let (plus, minus): (Vec<f64>, Vec<f64>) =
        (0..k).map(|i| (at(&[(i, h)]), at(&[(i, -h)]))).unzip();
    for i in 0..k {
        hess[(i, i)] = (plus[i] - 2.0 * f0 + minus[i]) / (h * h);
        for j in 0..i {
            let v = (at(&[(i, h), (j, h)]) - at(&[(i, h), (j, -h)]) - at(&[(i, -h), (j, h)])
                + at(&[(i, -h), (j, -h)]))
                / (4.0 * h * h);
            hess[(i, j)] = v;
            hess[(j, i)] = v;
        }
    }
    hess
}

/// One Jacobian column by central differences: (y(+) − y(−))/`width`, where `width` is the
/// distance between the two perturbed inputs.
pub(crate) fn central_column(plus: &[f64], minus: &[f64], width: f64) -> Vec<f64> {
    plus.iter()
        .zip(minus)
        .map(|(a, b)| (a - b) / width)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hessian_of_a_quadratic_is_exact() {
        let f = |x: &[f64]| 3.0 * x[0] * x[0] + x[0] * x[1] + 0.5 * x[1] * x[1];
        let h = hessian(&f, &[0.3, -0.2], f(&[0.3, -0.2]), 1e-3);
        for (got, want) in h.iter().zip([6.0, 1.0, 1.0, 1.0]) {
            assert!((got - want).abs() < 1e-6, "{h}");
        }
    }
}
