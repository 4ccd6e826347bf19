//! Leakage and friction laws of the fluid-power and tribology literature, as effects the
//! twin can switch on, and a random draw of one (law, path, size) from a seed, for
//! validating the diagnosis on physics it was not written for. Written from the textbook
//! formulas (docs/diagnosis.md, "Term library"), sharing no code with vanefit. SI units.
//!
//! Some of these laws are in vanefit's term library, some are not (the gas orifice √(ρ_u·Δp),
//! the turbulent Δp^(4/7), Saint-Venant, ISO 6358 with another critical ratio, the
//! exponential Stribeck curve, the power-law viscous loss, load-dependent friction, friction
//! pressed by the mean chamber pressure): a diagnosis must then name the path or balance
//! with the nearest law it has.

use super::motor::{iso6358_psi, RHO0_KG_M3, RT0_J_KG};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// A node of a leak path.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Node {
    /// The inlet volume V_1.
    V1,
    /// The outlet volume V_2.
    V2,
    /// The exhaust volume V_e.
    Ve,
    /// The atmosphere.
    Atm,
}

impl Node {
    /// Index into [p_1, p_2, p_e] (None: atmosphere).
    pub fn index(self) -> Option<usize> {
        match self {
            Node::V1 => Some(0),
            Node::V2 => Some(1),
            Node::Ve => Some(2),
            Node::Atm => None,
        }
    }

    /// Pressure at this node, Pa.
    pub fn pressure(self, p: [f64; 3], p_atm_pa: f64) -> f64 {
        self.index().map_or(p_atm_pa, |i| p[i])
    }

    /// Pressure at a typical operating point (near free speed at 0.73 MPa supply), Pa:
    /// where a drawn leak is given its size.
    pub fn typical_pa(self) -> f64 {
        match self {
            Node::V1 => 6.0e5,
            Node::V2 => 1.6e5,
            Node::Ve => 1.3e5,
            Node::Atm => 101_325.0,
        }
    }
}

/// The six leak paths: between the three volumes and from each to atmosphere.
pub const PATHS: [(Node, Node); 6] = [
    (Node::V1, Node::Ve),
    (Node::V2, Node::Ve),
    (Node::V1, Node::V2),
    (Node::V1, Node::Atm),
    (Node::V2, Node::Atm),
    (Node::Ve, Node::Atm),
];

/// Pressure difference below which a square-root or fractional-power law is taken linear
/// (finite slope at Δp = 0, where real gaps turn laminar), Pa.
const LINEAR_BELOW_PA: f64 = 500.0;

/// A leakage law: mass flow from a (pressure p_a) to b (p_b), kg/s, per unit coefficient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LeakLaw {
    /// Incompressible laminar gap (Hagen–Poiseuille, plane gap): ṁ = k·Δp.
    Laminar,
    /// Isothermal compressible laminar gap: ṁ = k·(p_a² − p_b²).
    CompressibleLaminar,
    /// Turbulent gap (Blasius friction factor): ṁ = k·sign(Δp)·|Δp|^(4/7).
    Turbulent,
    /// Fully rough / worn gap, flow growing with Δp² (the twin's earlier worn-vane leak).
    Quadratic,
    /// Sharp-edged orifice with the upstream gas density (Bernoulli):
    /// ṁ = k·sign(Δp)·√(ρ_u·|Δp|), ρ_u = p_u/(R·T0).
    GasOrifice,
    /// Isentropic nozzle (Saint-Venant–Wantzel), choked below the critical ratio 0.528:
    /// ṁ = k·p_u·Φ(p_d/p_u).
    SaintVenant,
    /// ISO 6358 with critical ratio `b` and k the sonic conductance: ṁ = k·ρ0·p_u·ψ(r, b).
    Iso6358 {
        /// Critical pressure ratio.
        b: f64,
    },
}

/// Ratio of specific heats of air.
const KAPPA: f64 = 1.4;

/// Saint-Venant–Wantzel flow function Φ(r) = √(2κ/(κ−1)·(r^(2/κ) − r^((κ+1)/κ))), held
/// at its maximum below the critical ratio, linear to 0 above r = 0.999.
fn saint_venant_phi(r: f64) -> f64 {
    let rc = (2.0 / (KAPPA + 1.0)).powf(KAPPA / (KAPPA - 1.0));
    let f = |r: f64| {
        (2.0 * KAPPA / (KAPPA - 1.0) * (r.powf(2.0 / KAPPA) - r.powf((KAPPA + 1.0) / KAPPA)))
            .max(0.0)
            .sqrt()
    };
    if r <= rc {
        f(rc)
    } else if r <= 0.999 {
        f(r)
    } else {
        f(0.999) * ((1.0 - r) / 0.001).max(0.0)
    }
}

/// `sign(x)·|x|^e`, linear below [`LINEAR_BELOW_PA`] (continuous there).
fn signed_power(x: f64, e: f64) -> f64 {
    let a = x.abs();
    let v = if a < LINEAR_BELOW_PA {
        LINEAR_BELOW_PA.powf(e) * a / LINEAR_BELOW_PA
    } else {
        a.powf(e)
    };
    v.copysign(x)
}

impl LeakLaw {
    /// Flow a → b per unit coefficient (negative: b → a).
    pub fn flow(self, pa: f64, pb: f64) -> f64 {
        let dp = pa - pb;
        let (pu, pd, sign) = if dp >= 0.0 {
            (pa, pb, 1.0)
        } else {
            (pb, pa, -1.0)
        };
        match self {
            LeakLaw::Laminar => dp,
            LeakLaw::CompressibleLaminar => pa * pa - pb * pb,
            LeakLaw::Turbulent => signed_power(dp, 4.0 / 7.0),
            LeakLaw::Quadratic => dp * dp.abs(),
            LeakLaw::GasOrifice => (pu / RT0_J_KG).sqrt() * signed_power(dp, 0.5),
            LeakLaw::SaintVenant => sign * pu * saint_venant_phi(pd / pu),
            LeakLaw::Iso6358 { b } => sign * RHO0_KG_M3 * pu * iso6358_psi(pd / pu, b),
        }
    }

    /// Short name for tables.
    pub fn name(self) -> String {
        match self {
            LeakLaw::Laminar => "laminar".into(),
            LeakLaw::CompressibleLaminar => "compressible laminar".into(),
            LeakLaw::Turbulent => "turbulent 4/7".into(),
            LeakLaw::Quadratic => "quadratic".into(),
            LeakLaw::GasOrifice => "gas orifice".into(),
            LeakLaw::SaintVenant => "Saint-Venant".into(),
            LeakLaw::Iso6358 { b } => format!("ISO 6358 b={b:.2}"),
        }
    }

    /// The same physics is already a base-model nozzle on this path (the exhaust nozzle
    /// V_e → atm, the leak conductances between the volumes): a drawn leak of a choked law
    /// there is only a change of a base parameter, not missing physics.
    pub fn in_base_model(self, from: Node, to: Node) -> bool {
        let choked = matches!(self, LeakLaw::SaintVenant | LeakLaw::Iso6358 { .. });
        choked && !matches!((from, to), (Node::V1, Node::Atm) | (Node::V2, Node::Atm))
    }
}

/// A leak along a path: `coefficient · law(p_from, p_to)` kg/s from `from` to `to`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Leak {
    /// Where the flow leaves.
    pub from: Node,
    /// Where it enters.
    pub to: Node,
    /// The law.
    pub law: LeakLaw,
    /// Its coefficient (SI per unit of the law).
    pub coefficient: f64,
}

impl Leak {
    /// The flow from → to, kg/s.
    pub fn flow_kg_s(&self, p: [f64; 3], p_atm_pa: f64) -> f64 {
        self.coefficient
            * self.law.flow(
                self.from.pressure(p, p_atm_pa),
                self.to.pressure(p, p_atm_pa),
            )
    }
}

/// A friction law (a loss torque, N·m, opposing the motion), beyond the base model's
/// Coulomb and viscous terms.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionLaw {
    /// Stribeck curve with exponential decay: (T_s − T_c)·exp(−|ω|/ω_s)·sign(ω).
    ExponentialStribeck {
        /// Static excess T_s − T_c, N·m.
        excess_nm: f64,
        /// Stribeck speed, rad/s.
        w_s_rad_s: f64,
    },
    /// Viscous loss growing with a power of the speed (mixed lubrication): c·sign(ω)·|ω|^1.5.
    ViscousPower {
        /// Coefficient, N·m/(rad/s)^1.5.
        c: f64,
    },
    /// Load-dependent Coulomb friction: μ·|T_air|·sign(ω) (a bearing loaded by the torque).
    LoadDependent {
        /// Fraction of the air torque, 1.
        mu: f64,
    },
    /// Coulomb friction of vanes pressed by the mean chamber pressure:
    /// k·max((p_1 + p_2)/2 − p_e, 0)·sign(ω).
    MeanPressure {
        /// N·m/Pa.
        k: f64,
    },
}

impl FrictionLaw {
    /// The loss torque, N·m, at pressures `p`, speed ω and air torque `t_air` (sign(ω)
    /// regularised as tanh(ω/ω_reg)).
    pub fn torque_nm(self, p: [f64; 3], w: f64, t_air: f64, w_reg: f64) -> f64 {
        let s = (w / w_reg).tanh();
        match self {
            FrictionLaw::ExponentialStribeck {
                excess_nm,
                w_s_rad_s,
            } => excess_nm * (-w.abs() / w_s_rad_s).exp() * s,
            FrictionLaw::ViscousPower { c } => c * w.abs().powf(1.5) * w.signum(),
            FrictionLaw::LoadDependent { mu } => mu * t_air.abs() * s,
            FrictionLaw::MeanPressure { k } => k * (0.5 * (p[0] + p[1]) - p[2]).max(0.0) * s,
        }
    }

    /// The full dry part at rest, N·m (a brake holding the rotor still overcomes it).
    pub fn static_nm(self, p: [f64; 3], t_air: f64) -> f64 {
        match self {
            FrictionLaw::ExponentialStribeck { excess_nm, .. } => excess_nm,
            FrictionLaw::ViscousPower { .. } => 0.0,
            FrictionLaw::LoadDependent { mu } => mu * t_air.abs(),
            FrictionLaw::MeanPressure { k } => k * (0.5 * (p[0] + p[1]) - p[2]).max(0.0),
        }
    }

    /// Short name for tables.
    pub fn name(self) -> &'static str {
        match self {
            FrictionLaw::ExponentialStribeck { .. } => "exponential Stribeck",
            FrictionLaw::ViscousPower { .. } => "viscous |w|^1.5",
            FrictionLaw::LoadDependent { .. } => "load-dependent Coulomb",
            FrictionLaw::MeanPressure { .. } => "mean-pressure Coulomb",
        }
    }
}

/// An effect drawn at random.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Drawn {
    /// A leak.
    Leak(Leak),
    /// A friction law.
    Friction(FrictionLaw),
}

impl Drawn {
    /// The effect in words, for tables.
    pub fn describe(&self) -> String {
        match self {
            Drawn::Leak(l) => format!(
                "leak {:?}->{:?} {} k={:.3e}",
                l.from,
                l.to,
                l.law.name(),
                l.coefficient
            ),
            Drawn::Friction(f) => format!("friction {} {f:?}", f.name()),
        }
    }
}

impl Drawn {
    /// This effect (drawn for the 3.8 cm³ reference motor) on a motor `s` times its
    /// displacement, by the geometric similarity of tests/twin/sizes.rs (lengths × s^⅓, the
    /// supply and so the typical pressures the same): a leak's coefficient × s^⅔ (the gap's
    /// area; its flow at the typical pressures then stays the same share of the motor's);
    /// the Stribeck excess × s and its speed × s^{-⅓} (torques ∝ s, speeds ∝ s^{-⅓}); the
    /// power-law viscous coefficient × s^{3/2} (the loss c·ω^{3/2} × s at the speeds ×
    /// s^{-⅓}); the mean-pressure coefficient × s (a torque at the same pressures); the
    /// load-dependent fraction μ unchanged (a share of the air torque).
    pub fn scaled(self, s: f64) -> Drawn {
        match self {
            Drawn::Leak(l) => Drawn::Leak(Leak {
                coefficient: l.coefficient * s.powf(2.0 / 3.0),
                ..l
            }),
            Drawn::Friction(f) => Drawn::Friction(match f {
                FrictionLaw::ExponentialStribeck {
                    excess_nm,
                    w_s_rad_s,
                } => FrictionLaw::ExponentialStribeck {
                    excess_nm: excess_nm * s,
                    w_s_rad_s: w_s_rad_s * s.powf(-1.0 / 3.0),
                },
                FrictionLaw::ViscousPower { c } => FrictionLaw::ViscousPower { c: c * s.powf(1.5) },
                FrictionLaw::LoadDependent { mu } => FrictionLaw::LoadDependent { mu },
                FrictionLaw::MeanPressure { k } => FrictionLaw::MeanPressure { k: k * s },
            }),
        }
    }
}

/// Factor drawn log-uniformly in [lo, hi].
fn log_uniform(rng: &mut Xoshiro256PlusPlus, lo: f64, hi: f64) -> f64 {
    (lo.ln() + rng.random::<f64>() * (hi / lo).ln()).exp()
}

/// One effect drawn from `seed`: two draws in three a leak (path uniform over [`PATHS`], law
/// uniform, redrawn while the base model already has it there, sized to carry 0.06–0.3 g/s
/// log-uniform at the nodes' typical pressures), else a friction law (loss of 6–20 mN·m at
/// a typical operating point; the Stribeck excess 1–3 times a base Coulomb torque of 20
/// mN·m, ω_s 3–30 rad/s).
pub fn draw(seed: u64) -> Drawn {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x1a75_0f1e_a4a6_e000);
    if rng.random::<f64>() < 2.0 / 3.0 {
        loop {
            let (from, to) = PATHS[rng.random_range(0..PATHS.len())];
            let law = match rng.random_range(0..7) {
                0 => LeakLaw::Laminar,
                1 => LeakLaw::CompressibleLaminar,
                2 => LeakLaw::Turbulent,
                3 => LeakLaw::Quadratic,
                4 => LeakLaw::GasOrifice,
                5 => LeakLaw::SaintVenant,
                _ => LeakLaw::Iso6358 {
                    b: 0.2 + 0.25 * rng.random::<f64>(),
                },
            };
            let q = log_uniform(&mut rng, 0.06e-3, 0.3e-3);
            if law.in_base_model(from, to) {
                continue;
            }
            let unit = law.flow(from.typical_pa(), to.typical_pa());
            return Drawn::Leak(Leak {
                from,
                to,
                law,
                coefficient: q / unit,
            });
        }
    }
    let loss = log_uniform(&mut rng, 6e-3, 20e-3);
    Drawn::Friction(match rng.random_range(0..4) {
        0 => FrictionLaw::ExponentialStribeck {
            excess_nm: 0.02 * (1.0 + 2.0 * rng.random::<f64>()),
            w_s_rad_s: log_uniform(&mut rng, 3.0, 30.0),
        },
        1 => FrictionLaw::ViscousPower {
            c: loss / 1000f64.powf(1.5),
        },
        // A typical air torque of 0.2 N·m.
        2 => FrictionLaw::LoadDependent { mu: loss / 0.2 },
        // A typical (p_1 + p_2)/2 − p_e of 2.5e5 Pa.
        _ => FrictionLaw::MeanPressure { k: loss / 2.5e5 },
    })
}
