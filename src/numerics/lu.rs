//! Dense LU factorisation of the 4×4 matrices of a motor's state (partial pivoting, on the
//! stack, no allocation), shared by the stiff integrator and the steady-state Newton.

use super::ode::{State, N_STATES};

/// LU factors of a 4×4 matrix with partial pivoting, on the stack: Rodas4 factors its step
/// matrix once per step and solves with it six times; the steady-state Newton factors one
/// per iteration.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lu {
    /// L below the diagonal (unit diagonal implied), U on and above it.
    a: [State; N_STATES],
    /// Row of the original matrix that ended up in each position.
    perm: [usize; N_STATES],
    /// 1/U_ii: six solves per factorisation multiply instead of divide.
    inv_diag: State,
}

impl Lu {
    /// Factors `a`; `None` when a pivot is zero or not finite (a singular step matrix).
    /// Plain index loops over the fixed size, so that the compiler unrolls them
    /// (with iterator adapters one factorisation took ~700 instructions). Always inlined:
    /// with vanefit compiled as one unit (Cargo.toml, [profile.release]), LLVM left it a
    /// call in Rodas4's step (+35 k instructions per evaluation).
    #[inline(always)]
    // Index loops on purpose: the pivot row and the row it updates are rows of one array.
    #[allow(clippy::needless_range_loop)]
    pub fn new(mut a: [State; N_STATES]) -> Option<Self> {
        let mut perm = [0, 1, 2, 3];
        for col in 0..N_STATES {
            let mut pivot = col;
            for r in col + 1..N_STATES {
                if a[r][col].abs() > a[pivot][col].abs() {
                    pivot = r;
                }
            }
            if a[pivot][col] == 0.0 || !a[pivot][col].is_finite() {
                return None;
            }
            a.swap(col, pivot);
            perm.swap(col, pivot);
            for r in col + 1..N_STATES {
                let m = a[r][col] / a[col][col];
                a[r][col] = m;
                for c in col + 1..N_STATES {
                    a[r][c] -= m * a[col][c];
                }
            }
        }
        let inv_diag = std::array::from_fn(|i| 1.0 / a[i][i]);
        Some(Self { a, perm, inv_diag })
    }

    /// x with A·x = b.
    #[inline]
    pub fn solve(&self, b: State) -> State {
        // `% N_STATES` is a no-op on a permutation of 0..4 that lets the compiler drop the
        // bounds checks (six solves per step).
        let mut x: State = std::array::from_fn(|i| b[self.perm[i] % N_STATES]);
        for r in 1..N_STATES {
            for c in 0..r {
                x[r] -= self.a[r][c] * x[c];
            }
        }
        for r in (0..N_STATES).rev() {
            for c in r + 1..N_STATES {
                x[r] -= self.a[r][c] * x[c];
            }
            x[r] *= self.inv_diag[r];
        }
        x
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lu_solves_like_nalgebra_and_rejects_singular_matrices() {
        // Needs pivoting (zero leading entry); checked against nalgebra's LU.
        let a = [
            [0.0, 2.0, -1.0, 4.0],
            [3.0, -1.0, 2.0, 0.5],
            [1.0, 1.0, 1.0, 1.0],
            [-2.0, 0.3, 5.0, 1.0],
        ];
        let b = [1.0, -2.0, 0.5, 3.0];
        let x = Lu::new(a).unwrap().solve(b);
        let m = nalgebra::Matrix4::from_fn(|i, j| a[i][j]);
        let want = m.lu().solve(&nalgebra::Vector4::from(b)).unwrap();
        for i in 0..4 {
            assert!((x[i] - want[i]).abs() < 1e-12, "{x:?} vs {want:?}");
        }
        let mut singular = a;
        singular[3] = [3.0, 1.0, 1.0, 4.5]; // row 0 + row 1
        assert!(
            Lu::new(singular).is_none() || {
                let y = Lu::new(singular).unwrap().solve(b);
                !y.iter().all(|v| v.is_finite() && v.abs() < 1e12)
            }
        );
    }
}
