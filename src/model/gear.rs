//! A gearbox on the motor's shaft (docs/formats.md, "Geared motors"): the figures of a
//! geared motor's page are those of its output shaft, and the model is the motor's. This is
//! the one place where the two shafts are related.
//!
//! With the ratio G = ω_motor/ω_out (a reduction has G > 1) and the gearbox efficiency η:
//!
//! ```text
//!     ω_out = ω/G        T_out = η·G·T        P_out = T_out·ω_out = η·P        ṁ unchanged
//! ```
//!
//! The loss is proportional to the transmitted torque (a tooth-mesh loss, as gearbox makers
//! state one efficiency); at free speed, where the output carries no torque, the gearbox
//! takes none either. A real gearbox's no-load drag (churning, seals, bearings) is not
//! modelled apart: it is a torque on the motor shaft that grows with speed, which a fit
//! takes into the motor's own Coulomb and viscous friction, so a geared motor's
//! motor-shaft parameters are the motor's with its gearbox's drag.
//!
//! When the page does not print the efficiency, it is the prior of [`Gear::prior`]: per
//! planetary stage a median of 0.95 with a 95 % range of about 0.90 to 1.0 (makers of
//! planetary gearboxes state 96–98 % per stage for industrial helical and spur stages and
//! "losses never exceed 3 % per stage", small gearheads lower; stages multiply: Design
//! World, "Miniature gearing and planetary gearing in haptic feedback", 2020,
//! <https://www.designworldonline.com/miniature-gearing-and-planetary-gearing-in-haptic-feedback/>;
//! "How efficient is a planetary gearbox? 97 % explained",
//! <https://planetarygeardrive.top/nn/application/how-efficient-is-a-planetary-gearbox-97-explained-5-ways-to-improve>),
//! and one stage per factor of 10 of the ratio (a planetary stage reduces up to about
//! 10:1). Its spread enters the fit as a nuisance gain on the page's torques and powers
//! (`objective::likelihood`), so the fit's intervals, and `predict`'s bands, hold it.

use crate::units::Quantity;

/// The largest reduction of one planetary stage: a ratio G takes ⌈log₁₀ G⌉ stages.
pub const STAGE_RATIO_MAX: f64 = 10.0;

/// Median efficiency of one gear stage when the page prints none.
pub const STAGE_EFFICIENCY: f64 = 0.95;

/// σ of ln η of one stage: 1.96·σ = 0.049, so 95 % of stages lie within 0.90 to 1.0.
pub const STAGE_LN_SD: f64 = 0.025;

/// A gearbox: ratio, efficiency and how well the efficiency is known.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gear {
    /// G = ω_motor/ω_out (> 0; a reduction has G > 1).
    pub ratio: f64,
    /// η, in (0, 1]: P_out = η·P.
    pub efficiency: f64,
    /// σ of ln η (0 when the page prints η).
    pub efficiency_ln_sd: f64,
    /// Whether the page printed η (`gear_efficiency`); otherwise it is [`Gear::prior`]'s.
    pub efficiency_printed: bool,
}

impl Gear {
    /// The gearbox of ratio `ratio` with the printed efficiency `efficiency`, or without
    /// one the prior's: `STAGE_EFFICIENCY`^n with σ(ln η) = n·`STAGE_LN_SD` for its
    /// n = ⌈log₁₀ G⌉ stages (of 1/G for a step-up; none at G = 1, which is no gearbox:
    /// η = 1 exactly). The stages of one gearbox share their make and lubrication, so
    /// their errors add rather than average.
    pub fn new(ratio: f64, efficiency: Option<f64>) -> Self {
        match efficiency {
            Some(eta) => Self {
                ratio,
                efficiency: eta,
                efficiency_ln_sd: 0.0,
                efficiency_printed: true,
            },
            None => Self::prior(ratio),
        }
    }

    /// The efficiency of a gearbox of ratio `ratio` whose page prints none (see
    /// [`Gear::new`]).
    pub fn prior(ratio: f64) -> Self {
        let n = Self::stages(ratio) as f64;
        Self {
            ratio,
            efficiency: STAGE_EFFICIENCY.powf(n),
            efficiency_ln_sd: STAGE_LN_SD * n,
            efficiency_printed: false,
        }
    }

    /// The planetary stages a ratio takes: ⌈log₁₀ max(G, 1/G)⌉ (0 at G = 1).
    pub fn stages(ratio: f64) -> u32 {
        let r = ratio.max(1.0 / ratio);
        // A whisker below an integer power of ten (the ratio as printed, 10 or 100) is
        // that power: no extra stage for rounding.
        (r.ln() / STAGE_RATIO_MAX.ln() - 1e-9).ceil().max(0.0) as u32
    }

    /// Output speed ω/G of motor speed `omega_rad_s`, rad/s.
    pub fn output_speed(&self, omega_rad_s: f64) -> f64 {
        omega_rad_s / self.ratio
    }

    /// Output torque η·G·T of motor torque `t_nm`, N·m.
    pub fn output_torque(&self, t_nm: f64) -> f64 {
        self.efficiency * self.ratio * t_nm
    }

    /// Output power η·P of motor power `p_w`, W.
    pub fn output_power(&self, p_w: f64) -> f64 {
        self.efficiency * p_w
    }

    /// Motor speed G·ω_out of output speed `omega_out_rad_s`, rad/s.
    pub fn motor_speed(&self, omega_out_rad_s: f64) -> f64 {
        omega_out_rad_s * self.ratio
    }

    /// Motor torque T_out/(η·G) of output torque `t_out_nm`, N·m.
    pub fn motor_torque(&self, t_out_nm: f64) -> f64 {
        t_out_nm / (self.efficiency * self.ratio)
    }

    /// Motor power P_out/η of output power `p_out_w`, W.
    pub fn motor_power(&self, p_out_w: f64) -> f64 {
        p_out_w / self.efficiency
    }

    /// A value of quantity `q` at the motor shaft moved to the output shaft: speeds,
    /// torques and powers by [`Gear::output_speed`], [`Gear::output_torque`] and
    /// [`Gear::output_power`]; every other quantity (air, pressures) is the same on both.
    pub fn to_output_shaft(&self, q: Quantity, motor_si: f64) -> f64 {
        match q {
            Quantity::Speed => self.output_speed(motor_si),
            Quantity::Torque => self.output_torque(motor_si),
            Quantity::Power => self.output_power(motor_si),
            _ => motor_si,
        }
    }

    /// A value of quantity `q` at the output shaft moved to the motor shaft (the inverse of
    /// [`Gear::to_output_shaft`]).
    pub fn to_motor_shaft(&self, q: Quantity, output_si: f64) -> f64 {
        match q {
            Quantity::Speed => self.motor_speed(output_si),
            Quantity::Torque => self.motor_torque(output_si),
            Quantity::Power => self.motor_power(output_si),
            _ => output_si,
        }
    }

    /// One line for people: "gearbox 4:1, efficiency 0.9025 (prior, 2 stages, 95 % 0.82–0.99)".
    pub fn describe(&self) -> String {
        let source = if self.efficiency_printed {
            "printed".to_string()
        } else {
            let (lo, hi) = (
                self.efficiency * (-1.96 * self.efficiency_ln_sd).exp(),
                (self.efficiency * (1.96 * self.efficiency_ln_sd).exp()).min(1.0),
            );
            format!(
                "not printed: prior, {} stage(s) of {STAGE_EFFICIENCY}, 95 % {lo:.3}–{hi:.3}",
                Self::stages(self.ratio)
            )
        };
        format!(
            "gearbox ratio {} (motor speed / output speed), efficiency {:.4} ({source})",
            self.ratio, self.efficiency
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stages_follow_the_ratio() {
        for (g, n) in [
            (1.0, 0),
            (3.6, 1),
            (10.0, 1),
            (10.5, 2),
            (60.0, 2),
            (100.0, 2),
            (300.0, 3),
            (0.25, 1),
        ] {
            assert_eq!(Gear::stages(g), n, "G = {g}");
        }
        assert_eq!(Gear::prior(1.0).efficiency, 1.0);
        assert_eq!(Gear::prior(1.0).efficiency_ln_sd, 0.0);
        let two = Gear::prior(29.0);
        assert!((two.efficiency - 0.9025).abs() < 1e-12);
        assert!((two.efficiency_ln_sd - 0.05).abs() < 1e-12);
    }

    /// Power is conserved but for η, and the two directions invert each other.
    #[test]
    fn the_shafts_relate_by_ratio_and_efficiency() {
        let g = Gear::new(4.0, Some(0.9));
        let (w, t) = (1000.0, 0.2);
        let (wo, to) = (g.output_speed(w), g.output_torque(t));
        assert!((wo * to - 0.9 * w * t).abs() < 1e-12);
        assert!((g.output_power(w * t) - wo * to).abs() < 1e-12);
        assert!((g.motor_speed(wo) - w).abs() < 1e-12);
        assert!((g.motor_torque(to) - t).abs() < 1e-15);
        assert!((g.motor_power(g.output_power(5.0)) - 5.0).abs() < 1e-12);
        assert!(g.describe().contains("printed"));
        assert!(Gear::new(29.0, None).describe().contains("prior"));
    }
}
