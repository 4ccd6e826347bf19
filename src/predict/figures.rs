//! The figures of one motor at every asked pressure, and their layout as one flat vector so
//! that a band is propagated to each of them alike.
//!
//! Layout, for each asked pressure in order: the seven catalogue figures
//! ([`super::ROW_FIGURES`]), the four correction factors ([`super::FACTORS`]), then for each
//! curve speed its torque, power and air. Two versions: as shown (the maximum power and
//! the figures at it on the speed grid) and smooth (the same at the continuous optimum of
//! P(ω)): the grid point moves in steps of Δ as the parameters change, so the bands are the
//! smooth figures' bands, centred on the shown values (the two differ by ½·P''·Δ² in power,
//! less than 1e-7 relative on a 1 rpm grid).

use super::{PredictError, PredictOptions};
use crate::model::gear::Gear;
use crate::model::motor::Motor;
use crate::sim::operating_point::{at_speeds, catalogue_row, CatalogueRow, OperatingPoint};

/// Catalogue figures per pressure.
pub(super) const N_ROW: usize = 7;
/// Correction factors per pressure.
pub(super) const N_FACTORS: usize = 4;
/// Curve figures per speed (torque, power, air).
pub(super) const N_CURVE: usize = 3;

/// Everything one motor gives for the asked options.
#[derive(Debug, Clone)]
pub(super) struct Outcome {
    /// The catalogue row at each asked pressure.
    pub rows: Vec<CatalogueRow>,
    /// The row at the reference pressure.
    pub reference: CatalogueRow,
    /// The curve at each asked pressure.
    pub curves: Vec<Vec<OperatingPoint>>,
}

impl Outcome {
    /// The figures of `motor`. The curves are at `curve_speeds` (rad/s, one list per asked
    /// pressure) where given, else at `curve_points` speeds from 0 to each free speed. The
    /// reference row is computed once and reused for an asked pressure equal to it, so that
    /// the factors there are exactly 1 for every motor.
    ///
    /// With a gearbox (`gear`) every figure is the output shaft's (`Gear`'s law), and
    /// `curve_speeds` are output speeds: the motor is solved at G times them, and at the
    /// maximum power on a grid G times as fine, so that the output's figures lie on the
    /// asked grid as an ungeared motor's do.
    pub fn of(
        motor: &Motor,
        options: &PredictOptions,
        curve_speeds: Option<&[Vec<f64>]>,
        gear: Option<&Gear>,
    ) -> Result<Self, PredictError> {
        let ratio = gear.map_or(1.0, |g| g.ratio);
        let grid = options.speed_grid_rad_s * ratio;
        let row_at = |p: f64| {
            catalogue_row(motor, &options.conditions(p), grid).map_err(|source| {
                PredictError::AtPressure {
                    p_supply_pa: p,
                    source,
                }
            })
        };
        let reference = row_at(options.reference_pa)?;
        let rows = options
            .pressures_pa
            .iter()
            .map(|p| {
                if *p == options.reference_pa {
                    Ok(reference)
                } else {
                    row_at(*p)
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        let n = options.curve_points;
        let curves = rows
            .iter()
            .enumerate()
            .map(|(i, r)| {
                let speeds: Vec<f64> = match curve_speeds {
                    Some(s) => s[i].iter().map(|w| w * ratio).collect(),
                    None => (0..n)
                        .map(|k| r.free_speed_rad_s * k as f64 / (n - 1) as f64)
                        .collect(),
                };
                at_speeds(motor, &options.conditions(r.p_supply_pa), &speeds).map_err(|e| {
                    PredictError::AtPressure {
                        p_supply_pa: r.p_supply_pa,
                        source: e.into(),
                    }
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let motor_shaft = Self {
            rows,
            reference,
            curves,
        };
        Ok(match gear {
            Some(g) => motor_shaft.at_output(g),
            None => motor_shaft,
        })
    }

    /// The same figures at a gearbox's output shaft: speeds ÷ G, torques × η·G, powers × η,
    /// air unchanged (`model::gear`).
    fn at_output(self, g: &Gear) -> Self {
        let row = |r: CatalogueRow| CatalogueRow {
            free_speed_rad_s: g.output_speed(r.free_speed_rad_s),
            max_power_w: g.output_power(r.max_power_w),
            speed_at_max_power_rad_s: g.output_speed(r.speed_at_max_power_rad_s),
            torque_at_max_power_nm: g.output_torque(r.torque_at_max_power_nm),
            stall_torque_nm: g.output_torque(r.stall_torque_nm),
            speed_grid_rad_s: g.output_speed(r.speed_grid_rad_s),
            optimum: point_at_output(g, r.optimum),
            ..r
        };
        Self {
            rows: self.rows.into_iter().map(row).collect(),
            reference: row(self.reference),
            curves: self
                .curves
                .into_iter()
                .map(|c| c.into_iter().map(|p| point_at_output(g, p)).collect())
                .collect(),
        }
    }

    /// The flat vector of figures (see the module documentation), smooth or as shown.
    pub(crate) fn flat(&self, smooth: bool) -> Vec<f64> {
        let mut out = Vec::new();
        for (row, curve) in self.rows.iter().zip(&self.curves) {
            out.extend(row_figures(row, smooth));
            out.extend(factors(row, &self.reference, smooth));
            for p in curve {
                out.extend([p.torque_nm, p.power_w, p.flow1_kg_s]);
            }
        }
        out
    }
}

/// An operating point at a gearbox's output shaft.
fn point_at_output(g: &Gear, p: OperatingPoint) -> OperatingPoint {
    OperatingPoint {
        speed_rad_s: g.output_speed(p.speed_rad_s),
        torque_nm: g.output_torque(p.torque_nm),
        power_w: g.output_power(p.power_w),
        ..p
    }
}

/// The catalogue figures of a row in [`super::ROW_FIGURES`] order, SI.
pub(super) fn row_figures(r: &CatalogueRow, smooth: bool) -> [f64; N_ROW] {
    let at_max = if smooth {
        let o = &r.optimum;
        [o.power_w, o.speed_rad_s, o.torque_nm]
    } else {
        [
            r.max_power_w,
            r.speed_at_max_power_rad_s,
            r.torque_at_max_power_nm,
        ]
    };
    let air_at_max = if smooth {
        r.optimum.flow1_kg_s
    } else {
        r.air_at_max_power_kg_s
    };
    [
        r.free_speed_rad_s,
        at_max[0],
        at_max[1],
        at_max[2],
        r.stall_torque_nm,
        air_at_max,
        r.air_at_free_speed_kg_s,
    ]
}

/// The correction factors of a row against the reference row, in [`super::FACTORS`]
/// order: maximum power, free speed, stall torque and air at maximum power, each divided by
/// the same figure at the reference pressure.
pub(super) fn factors(
    r: &CatalogueRow,
    reference: &CatalogueRow,
    smooth: bool,
) -> [f64; N_FACTORS] {
    let (a, b) = (row_figures(r, smooth), row_figures(reference, smooth));
    [a[1] / b[1], a[0] / b[0], a[4] / b[4], a[5] / b[5]]
}
