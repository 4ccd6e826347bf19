//! The displacement of a motor whose catalogue page does not print it, estimated from the
//! page itself (docs/estimation.md, "A page without a displacement").
//!
//! The steady model is exactly similar under the registry's size laws
//! (`ParamSpec::size_exponent`):
//! a motor s = V_disp/3.8 cm³ times AR034-11 with every default scaled has s × its torques,
//! s^⅔ × its flows and powers and s^−⅓ × its speeds at every supply pressure. So the
//! torque per supply pressure (∝ V_disp) and the air per revolution at free speed
//! (ṁ/ω ∝ V_disp) tell the size, while port sizes, which differ between makers, move speeds
//! and flows but hardly these two ratios. The estimate here is the first step:
//!
//! 1. **Similarity estimate.** χ²(s) of the page at the AR034-11 motor scaled to s (the
//!    likelihood's rows, each with its reading tolerance), minimised over ln s: a scan from
//!    0.05 to 2000 cm³, then Brent's minimiser between the scan's neighbours of its best point.
//! 2. **Its interval**, linearised at that motor: the Jacobian J of the normalised residuals
//!    with respect to ln s (every size-scaled parameter moving with it) and to the ln θ of the
//!    parameters a fit estimates by default (each on its own, about its size-scaled median),
//!    the posterior precision H = JᵀJ + diag(0, 1/σ²_prior) (a flat prior on ln s, the motor
//!    prior on the others) and σ_ln s = √(H⁻¹)₀₀: the spread the page leaves in the size once
//!    the ports, leaks and friction of real motors may differ from the scaled defaults.
//!
//! The fit then estimates `v_disp` with every other parameter, the priors' medians and the
//! fixed size-dependent parameters following it (`estimate::problem::prior`, `estimate::problem::space`), and
//! its profile interval is the one reported with the fit.

use crate::data::fitfile::FitFile;
use crate::data::motor::MotorSection;
use crate::estimate::problem::fit_data::FitData;
use crate::estimate::problem::prior::Prior;
use crate::model::effects::EffectSet;
use crate::model::motor::Motor;
use crate::model::params::MotorParams;
use crate::model::params::{ParamId, DEFAULT_ESTIMATED_IDS};
use crate::numerics::scalar::brent_minimize;
use crate::numerics::DefaultSolver;
use nalgebra::DMatrix;

/// The normal quantile of a two-sided 95 % range.
const Z95: f64 = 1.959_963_984_540_054;
/// The scan's range of displacements, m³ (0.05 to 2000 cm³: beyond every vane motor sold).
const SCAN_M3: (f64, f64) = (0.05e-6, 2000e-6);
/// Points of the scan (a factor of about 1.3 between neighbours).
const SCAN_POINTS: usize = 41;
/// Step of the central differences in ln θ and ln s.
const LOG_STEP: f64 = 1e-3;

/// A displacement estimated from a page, with its 95 % interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DisplacementEstimate {
    /// The estimate, m³.
    pub v_disp_m3: f64,
    /// Its 95 % interval, m³ (linearised; see the module documentation).
    pub ci95_m3: [f64; 2],
}

impl DisplacementEstimate {
    /// "displacement estimated from the page: 4.1 cm³ [3.8, 4.5]".
    pub fn describe(&self) -> String {
        describe_cm3(self.v_disp_m3, self.ci95_m3)
    }
}

/// "displacement estimated from the page: 4.1 cm³ [3.8, 4.5]" (3 significant digits) of a
/// value and its 95 % interval in m³.
pub fn describe_cm3(v_m3: f64, ci95_m3: [f64; 2]) -> String {
    format!(
        "displacement estimated from the page: {} cm³ [{}, {}] (95 %)",
        cm3_digits(v_m3),
        cm3_digits(ci95_m3[0]),
        cm3_digits(ci95_m3[1])
    )
}

/// The fit's displacement (m³) with the 95 % interval that the fit file gives it: the
/// profile interval `ci95` where it holds the estimate, else the verdict's ends (`None`:
/// open), as [`describe_fitted_cm3`] words it. An interval is the estimate's own or none:
/// the page's similarity estimate's interval belongs to another estimate.
pub fn fitted_interval(
    v_m3: f64,
    ci95: Option<[f64; 2]>,
    verdict: Option<[Option<f64>; 2]>,
) -> Option<[Option<f64>; 2]> {
    match ci95 {
        Some([lo, hi]) if lo <= v_m3 && v_m3 <= hi => Some([Some(lo), Some(hi)]),
        _ => verdict
            .filter(|[lo, hi]| lo.is_none_or(|lo| lo <= v_m3) && hi.is_none_or(|hi| v_m3 <= hi)),
    }
}

/// "displacement estimated from the page: 4.1 cm³ [3.8, open] (95 %)", or "(no 95 %
/// interval: …)" without one ([`fitted_interval`]).
pub fn describe_fitted_cm3(v_m3: f64, interval: Option<[Option<f64>; 2]>) -> String {
    match interval {
        Some([Some(lo), Some(hi)]) => describe_cm3(v_m3, [lo, hi]),
        Some([lo, hi]) => {
            let end = |e: Option<f64>| e.map_or("open".to_string(), cm3_digits);
            format!(
                "displacement estimated from the page: {} cm³ [{}, {}] (95 %; the page does not bound it on the open side)",
                cm3_digits(v_m3),
                end(lo),
                end(hi)
            )
        }
        None => format!(
            "displacement estimated from the page: {} cm³ (no 95 % interval: the fit did not bound it)",
            cm3_digits(v_m3)
        ),
    }
}

/// The displacement a fit file gives a page that does not print it, in words, with the
/// interval the file gives it ([`fitted_interval`]: the estimate's own, never the
/// similarity estimate's).
pub fn describe_fitted(file: &FitFile) -> String {
    let name = ParamId::V_DISP.name();
    let v = file.params.v_disp();
    let ci = file.ci95.iter().find(|(n, _)| n == name).map(|(_, c)| *c);
    let verdict = file
        .verdicts
        .iter()
        .find(|d| d.name == name)
        .map(|d| d.bounds95);
    describe_fitted_cm3(v, fitted_interval(v, ci, verdict))
}

/// A volume in m³ as cm³ to 3 significant digits.
fn cm3_digits(v_m3: f64) -> String {
    let v = v_m3 * 1e6;
    let d = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    format!("{v:.d$}")
}

/// Whether a `[motor]` table leaves the displacement to be estimated: no displacement and
/// no geometry.
pub fn displacement_missing(motor: &MotorSection) -> bool {
    motor.displacement_m3.is_none() && matches!(motor.geometry(), Ok(None))
}

/// The nominal motor of `section` at displacement `v_m3` (its defaults scaled to it).
fn nominal_at(section: &MotorSection, v_m3: f64) -> Option<MotorParams> {
    let mut at = section.clone();
    at.displacement_m3 = Some(v_m3);
    at.nominal_params().ok()
}

/// The page's normalised residuals at a motor (`None`: the simulation failed).
fn residuals(data: &FitData, params: MotorParams) -> Option<Vec<f64>> {
    let solver = DefaultSolver::default();
    data.target.residuals(
        &data.smoothed,
        &Motor::new(params, EffectSet::empty()),
        &solver,
    )
}

/// χ² of the page at the nominal motor of displacement e^`ln_v` (a large finite value where
/// it cannot be simulated, so that the scan passes over it).
fn chi2_at(data: &FitData, section: &MotorSection, ln_v: f64) -> f64 {
    nominal_at(section, ln_v.exp())
        .and_then(|p| residuals(data, p))
        .map_or(1e300, |r| r.iter().map(|x| x * x).sum())
}

/// The displacement of a page (see the module documentation), `None` when no displacement
/// in the scan's range gives a motor the page can be simulated at.
pub fn from_page(data: &FitData, section: &MotorSection) -> Option<DisplacementEstimate> {
    let (lo, hi) = (SCAN_M3.0.ln(), SCAN_M3.1.ln());
    let step = (hi - lo) / (SCAN_POINTS - 1) as f64;
    let scan: Vec<(f64, f64)> = (0..SCAN_POINTS)
        .map(|i| {
            let x = lo + step * i as f64;
            (x, chi2_at(data, section, x))
        })
        .collect();
    let best = scan
        .iter()
        .enumerate()
        .min_by(|a, b| a.1 .1.total_cmp(&b.1 .1))
        .map(|(i, _)| i)?;
    if scan[best].1 >= 1e300 {
        return None;
    }
    let (a, b) = (
        scan[best.saturating_sub(1)].0,
        scan[(best + 1).min(SCAN_POINTS - 1)].0,
    );
    let (ln_v, _) = brent_minimize(
        |x| Ok::<f64, ()>(chi2_at(data, section, x)),
        a,
        b,
        1e-6,
        1e-6,
    )
    .ok()?;
    let v = ln_v.exp();
    let sd = size_sd(data, section, v).unwrap_or(f64::INFINITY);
    let half = (Z95 * sd).min(700.0);
    Some(DisplacementEstimate {
        v_disp_m3: v,
        ci95_m3: [v * (-half).exp(), v * half.exp()],
    })
}

/// σ of ln V_disp at the nominal motor of displacement `v` (module documentation, step 2).
fn size_sd(data: &FitData, section: &MotorSection, v: f64) -> Option<f64> {
    let nominal = nominal_at(section, v)?;
    let prior = Prior::for_motor(&nominal);
    let r0 = residuals(data, nominal.clone())?;
    let n = r0.len();
    let ids: Vec<ParamId> = DEFAULT_ESTIMATED_IDS
        .iter()
        .copied()
        .filter(|id| prior.term(*id).is_some())
        .collect();
    let mut jac = DMatrix::<f64>::zeros(n, ids.len() + 1);
    let column = |plus: Vec<f64>, minus: Vec<f64>, jac: &mut DMatrix<f64>, j: usize| {
        for i in 0..n.min(plus.len()).min(minus.len()) {
            jac[(i, j)] = (plus[i] - minus[i]) / (2.0 * LOG_STEP);
        }
    };
    let at_size = |f: f64| nominal_at(section, v * f).and_then(|p| residuals(data, p));
    column(
        at_size(LOG_STEP.exp())?,
        at_size((-LOG_STEP).exp())?,
        &mut jac,
        0,
    );
    for (j, id) in ids.iter().enumerate() {
        let x = nominal.value(*id);
        let at = |f: f64| {
            let p = nominal.with_value(*id, x * f).ok()?;
            residuals(data, p)
        };
        column(at(LOG_STEP.exp())?, at((-LOG_STEP).exp())?, &mut jac, j + 1);
    }
    let mut h = jac.transpose() * &jac;
    for (j, id) in ids.iter().enumerate() {
        let sd = prior.term(*id)?.sd_ln;
        h[(j + 1, j + 1)] += 1.0 / (sd * sd);
    }
    let cov = h.try_inverse()?;
    let var = cov[(0, 0)];
    (var.is_finite() && var > 0.0).then(|| var.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An estimate is stated with an interval that holds it, or with none: never with
    /// another estimate's interval (issue 44: "1000 cm³ [178, 264] (95 %)").
    #[test]
    fn an_estimate_lies_inside_its_own_interval() {
        let v = 1000e-6;
        // A profile interval that holds it is the one stated.
        let held = fitted_interval(v, Some([800e-6, 1200e-6]), None);
        assert_eq!(held, Some([Some(800e-6), Some(1200e-6)]));
        assert!(describe_fitted_cm3(v, held).contains("1000 cm³ [800, 1200] (95 %)"));
        // One that does not is dropped for the verdict's ends, open where the profile is.
        let open = fitted_interval(v, Some([178e-6, 264e-6]), Some([Some(500e-6), None]));
        assert_eq!(open, Some([Some(500e-6), None]));
        assert!(describe_fitted_cm3(v, open).contains("1000 cm³ [500, open]"));
        // A verdict that does not hold it either: no interval, said so.
        let none = fitted_interval(
            v,
            Some([178e-6, 264e-6]),
            Some([Some(178e-6), Some(264e-6)]),
        );
        assert_eq!(none, None);
        let text = describe_fitted_cm3(v, none);
        assert!(
            text.contains("1000 cm³ (no 95 % interval") && !text.contains('['),
            "{text}"
        );
    }
}
