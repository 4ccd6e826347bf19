//! The twin's motor: docs/model.md from "Cycle work and torque" to "Parameters" (and the
//! effects of its "Missing-physics catalog" the twin supports), written from the docs and the
//! paper only. SI units throughout: Pa absolute, kg/s, rad/s, N·m, m³.

/// Specific gas constant of air R, J/(kg·K) (docs/model.md).
pub const R_J_KG_K: f64 = 287.0;
/// Reference temperature T0, K (docs/model.md); the volumes are isothermal at T0.
pub const T0_K: f64 = 293.15;
/// R·T0, J/kg.
pub const RT0_J_KG: f64 = R_J_KG_K * T0_K;
/// ISO 6358 reference density ρ0, kg/m³ (docs/model.md).
pub const RHO0_KG_M3: f64 = 1.185;
/// Standard atmosphere, Pa.
pub const P_ATM_PA: f64 = 101_325.0;
/// Speed scale ω_b of the forward/reverse torque blend, rad/s (docs/model.md,
/// "Cycle work and torque").
pub const OMEGA_BLEND_RAD_S: f64 = 1.0;
/// Pressure ratio above which a nozzle's flow is laminar (docs/model.md, "Lumped volumes and
/// nozzles").
pub const R_LAMINAR: f64 = 0.999;

/// Breakaway (Stribeck) friction, `breakaway_friction` (docs/model.md, "Missing-physics catalog"):
/// T_f = (T_c + (T_s − T_c)·exp(−(ω/ω_s)²))·tanh(ω/ω_reg) + d·ω.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Breakaway {
    /// Static friction T_s, N·m (`t_static`).
    pub t_static_nm: f64,
    /// Stribeck speed ω_s, rad/s (`w_stribeck`).
    pub w_stribeck_rad_s: f64,
}

/// Vanes seal better at speed, `speed_dependent_leakage` (docs/model.md, "Missing-physics
/// catalog"): the three leak
/// conductances c_1e, c_2e, c_12 are multiplied by 1 + g/(1 + (ω/ω_seal)²).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SealLeakage {
    /// Relative extra leakage at standstill g, 1 (`g_seal`).
    pub g_seal: f64,
    /// Sealing speed ω_seal, rad/s (`w_seal`).
    pub w_seal_rad_s: f64,
}

/// A vane motor: the parameters of (docs/model.md, "Parameters") (names as there) and optional
/// effects.
#[derive(Debug, Clone, PartialEq)]
pub struct TwinMotor {
    /// Sonic conductance supply → V_1 (nozzle in_1), m³/(s·Pa).
    pub c_in1: f64,
    /// Sonic conductance V_2 → port 2 (nozzle out_2), m³/(s·Pa).
    pub c_out2: f64,
    /// Sonic conductance V_e → atmosphere (nozzle EXT), m³/(s·Pa).
    pub c_ext: f64,
    /// Leak conductance V_1 → V_e (1_Ext), m³/(s·Pa).
    pub c_1e: f64,
    /// Leak conductance V_2 → V_e (2_Ext), m³/(s·Pa).
    pub c_2e: f64,
    /// Leak conductance V_1 → V_2 (1_2), m³/(s·Pa).
    pub c_12: f64,
    /// Critical pressure ratio b of every motor nozzle, 1.
    pub b_crit: f64,
    /// Number of vanes z, 1.
    pub z: f64,
    /// Nominal displacement V_disp = z·V_fill, m³.
    pub v_disp: f64,
    /// Expansion ratio ε = V_exp/V_fill, 1.
    pub eps: f64,
    /// Dead volume per compartment V_d, m³.
    pub v_dead: f64,
    /// Polytropic index n (1 ≤ n ≤ 1.4), 1.
    pub n_poly: f64,
    /// Lumped volume at stator inlet 1, m³.
    pub vol1: f64,
    /// Lumped volume at stator inlet 2, m³.
    pub vol2: f64,
    /// Lumped volume at the exhaust inlet e, m³.
    pub vole: f64,
    /// Inertia of rotor, coupling and brake J, kg·m².
    pub inertia: f64,
    /// Coulomb friction T_c, N·m.
    pub t_coulomb: f64,
    /// Viscous friction d, N·m·s/rad.
    pub visc: f64,
    /// Friction regularisation speed ω_reg, rad/s.
    pub w_reg: f64,
    /// `breakaway_friction` (docs/model.md, "Missing-physics catalog").
    pub breakaway_friction: Option<Breakaway>,
    /// `vane_friction_speed_squared` (docs/model.md, "Missing-physics catalog"): c_w2 in
    /// N·m·s²/rad², extra torque c_w2·ω·|ω|.
    pub vane_friction_speed_squared: Option<f64>,
    /// `speed_dependent_leakage` (docs/model.md, "Missing-physics catalog").
    pub speed_dependent_leakage: Option<SealLeakage>,
    /// Worn vane tips: internal leak V_1 → V_e, ṁ = k·(p_1 − p_e)·|p_1 − p_e| with k in
    /// kg/(s·Pa²). Not in vanefit's catalogue.
    pub leak_1e_dp2_kg_s_pa2: Option<f64>,
    /// Leakage and friction laws of the literature (docs/diagnosis.md, "Term library"),
    /// most of them not in vanefit's catalogue ([`super::laws`]).
    pub laws: Vec<super::laws::Drawn>,
}

impl Default for TwinMotor {
    /// Motor AR034-11 with the defaults of (docs/model.md, "Parameters") (paper appendix
    /// conductances).
    fn default() -> Self {
        Self {
            c_in1: 6.758282e-9,
            c_out2: 6.758282e-9,
            c_ext: 1.170707e-8,
            c_1e: 2.077886e-9,
            c_2e: 2.077886e-9,
            c_12: 7.616275e-10,
            b_crit: 0.5,
            z: 5.0,
            v_disp: 3.8e-6,
            eps: 1.071,
            v_dead: 0.10e-6,
            n_poly: 1.3,
            vol1: 2e-6,
            vol2: 2e-6,
            vole: 2e-6,
            inertia: 2e-4,
            t_coulomb: 0.02,
            visc: 6e-5,
            w_reg: 0.2,
            breakaway_friction: None,
            vane_friction_speed_squared: None,
            speed_dependent_leakage: None,
            leak_1e_dp2_kg_s_pa2: None,
            laws: Vec::new(),
        }
    }
}

impl TwinMotor {
    /// This motor's base parameters with `other`'s optional effects.
    pub fn with_effects_of(self, other: &TwinMotor) -> TwinMotor {
        TwinMotor {
            breakaway_friction: other.breakaway_friction,
            vane_friction_speed_squared: other.vane_friction_speed_squared,
            speed_dependent_leakage: other.speed_dependent_leakage,
            leak_1e_dp2_kg_s_pa2: other.leak_1e_dp2_kg_s_pa2,
            laws: other.laws.clone(),
            ..self
        }
    }
}

/// ISO 6358 flow function ψ(r) with critical ratio b (docs/model.md, "Lumped volumes and
/// nozzles"): 1 for r ≤ b,
/// √(1 − ((r − b)/(1 − b))²) up to r_lam = 0.999, then linear to 0 at r = 1 (laminar
/// extension, continuous at r_lam, finite slope everywhere).
pub fn iso6358_psi(r: f64, b: f64) -> f64 {
    let subsonic = |r: f64| {
        let x = (r - b) / (1.0 - b);
        (1.0 - x * x).max(0.0).sqrt()
    };
    if r <= b {
        1.0
    } else if r <= R_LAMINAR {
        subsonic(r)
    } else {
        subsonic(R_LAMINAR) * ((1.0 - r) / (1.0 - R_LAMINAR)).max(0.0)
    }
}

/// Mass flow through an ISO 6358 nozzle from side a to side b, kg/s (negative when the air
/// flows from b to a, by symmetry): ṁ = C·ρ0·p_u·ψ(p_d/p_u) at T_u = T0 (docs/model.md,
/// "Lumped volumes and nozzles").
pub fn nozzle_flow_kg_s(c_m3_s_pa: f64, b: f64, pa_pa: f64, pb_pa: f64) -> f64 {
    if pa_pa >= pb_pa {
        c_m3_s_pa * RHO0_KG_M3 * pa_pa * iso6358_psi(pb_pa / pa_pa, b)
    } else {
        -c_m3_s_pa * RHO0_KG_M3 * pb_pa * iso6358_psi(pa_pa / pb_pa, b)
    }
}

/// (e^(a·l) − 1)/a, with its limit l at a = 0 (accurate for tiny a through expm1).
fn expm1_over(a: f64, l: f64) -> f64 {
    if a == 0.0 {
        l
    } else {
        (a * l).exp_m1() / a
    }
}

/// Mean torque of a cycle driven at pressure p_a into the compartment, discharged at p_b and
/// exhausting at p_e, with positive rotation: T = z·W/(2π), where ((docs/model.md,
/// "Cycle work and torque"), work by the air)
///
/// W = (p_a − p_b)(V_fill − V_d) + p_a·V_fill·(1 − ε^(1−n))/(n−1) − p_e·V_exp·(ε^(n−1) − 1)/(n−1)
///
/// with V_fill = V_disp/z and V_exp = ε·V_fill. Both quotients are evaluated as
/// expm1(±(n−1)·ln ε)/(±(n−1)), whose limit at n = 1 is ln ε (isothermal cycle).
pub fn cycle_torque_nm(m: &TwinMotor, pa_pa: f64, pb_pa: f64, pe_pa: f64) -> f64 {
    let v_fill_m3 = m.v_disp / m.z;
    let v_exp_m3 = m.eps * v_fill_m3;
    let ln_eps = m.eps.ln();
    let k = m.n_poly - 1.0;
    let expansion = expm1_over(-k, ln_eps); // (1 − ε^(1−n))/(n−1)
    let compression = expm1_over(k, ln_eps); // (ε^(n−1) − 1)/(n−1)
    let work_j = (pa_pa - pb_pa) * (v_fill_m3 - m.v_dead) + pa_pa * v_fill_m3 * expansion
        - pe_pa * v_exp_m3 * compression;
    m.z * work_j / (2.0 * std::f64::consts::PI)
}

/// Air torque of the ideal motor, N·m (docs/model.md, "Cycle work and torque"):
/// forward T_fwd = z·W(p_1, p_2)/(2π),
/// reverse T_rev = −z·W(p_2, p_1)/(2π), blended by ½(1 ± tanh(ω/ω_b)), ω_b = 1 rad/s.
pub fn air_torque_nm(m: &TwinMotor, p_pa: [f64; 3], w_rad_s: f64) -> f64 {
    let [p1, p2, pe] = p_pa;
    let fwd = cycle_torque_nm(m, p1, p2, pe);
    let rev = -cycle_torque_nm(m, p2, p1, pe);
    let s = (w_rad_s / OMEGA_BLEND_RAD_S).tanh();
    0.5 * (1.0 + s) * fwd + 0.5 * (1.0 - s) * rev
}

/// Friction torque T_f(ω), N·m (docs/model.md, "Mechanics and friction" and
/// "Missing-physics catalog"): T_c·tanh(ω/ω_reg) + d·ω, with T_c
/// replaced by T_c + (T_s − T_c)·exp(−(ω/ω_s)²) under breakaway friction, plus c_w2·ω·|ω|
/// under vane friction ∝ ω².
pub fn friction_torque_nm(m: &TwinMotor, w_rad_s: f64) -> f64 {
    let dry_nm = match m.breakaway_friction {
        Some(b) => {
            let x = w_rad_s / b.w_stribeck_rad_s;
            m.t_coulomb + (b.t_static_nm - m.t_coulomb) * (-x * x).exp()
        }
        None => m.t_coulomb,
    };
    let vane_nm = m
        .vane_friction_speed_squared
        .map_or(0.0, |c_w2| c_w2 * w_rad_s * w_rad_s.abs());
    dry_nm * (w_rad_s / m.w_reg).tanh() + m.visc * w_rad_s + vane_nm
}

/// Full dry friction at rest, N·m: T_s under breakaway friction, else T_c ((docs/model.md,
/// "Reference experiments"): the
/// datasheet's stall torque is the air torque less this).
pub fn static_friction_nm(m: &TwinMotor) -> f64 {
    m.breakaway_friction.map_or(m.t_coulomb, |b| b.t_static_nm)
}

/// Factor on the three leak conductances, 1 + g/(1 + (ω/ω_seal)²) (docs/model.md,
/// "Missing-physics catalog"), else 1.
pub fn leak_factor(m: &TwinMotor, w_rad_s: f64) -> f64 {
    m.speed_dependent_leakage.map_or(1.0, |s| {
        let x = w_rad_s / s.w_seal_rad_s;
        1.0 + s.g_seal / (1.0 + x * x)
    })
}

/// Mass flows of the ideal motor into V_1, V_2, V_e, kg/s (docs/model.md, "Flows through
/// the ideal motor", paper eqs. 16–18).
/// Forward: out of V_1 p_1·ω·V_disp/(2π·RT0), into V_2 p_e·ω·ε·V_disp/(2π·RT0), the rest
/// into V_e; reverse rotation mirrors ports 1 and 2. The three sum to zero exactly.
pub fn ideal_motor_flows_kg_s(m: &TwinMotor, p_pa: [f64; 3], w_rad_s: f64) -> [f64; 3] {
    let [p1, p2, pe] = p_pa;
    let q_m3_rad = m.v_disp / (2.0 * std::f64::consts::PI * RT0_J_KG);
    let w_abs = w_rad_s.abs();
    let from_in_kg_s = |p_in: f64| p_in * w_abs * q_m3_rad;
    let to_out_kg_s = pe * w_abs * m.eps * q_m3_rad;
    if w_rad_s >= 0.0 {
        let from1 = from_in_kg_s(p1);
        [-from1, to_out_kg_s, from1 - to_out_kg_s]
    } else {
        let from2 = from_in_kg_s(p2);
        [to_out_kg_s, -from2, from2 - to_out_kg_s]
    }
}

/// Net mass flow into V_1, V_2, V_e, kg/s, from everything inside the motor: the ideal motor,
/// the three leaks (1_Ext, 2_Ext, 1_2, scaled by [`leak_factor`]), the optional Δp² leak
/// V_1 → V_e and the exhaust nozzle EXT to atmosphere. Port flows are added by the caller.
pub fn internal_flows_kg_s(m: &TwinMotor, p_pa: [f64; 3], w_rad_s: f64, p_atm_pa: f64) -> [f64; 3] {
    let [p1, p2, pe] = p_pa;
    let [mut q1, mut q2, mut qe] = ideal_motor_flows_kg_s(m, p_pa, w_rad_s);
    let f = leak_factor(m, w_rad_s);
    let b = m.b_crit;
    let mut leak_1e = nozzle_flow_kg_s(f * m.c_1e, b, p1, pe);
    if let Some(k) = m.leak_1e_dp2_kg_s_pa2 {
        leak_1e += k * (p1 - pe) * (p1 - pe).abs();
    }
    let leak_2e = nozzle_flow_kg_s(f * m.c_2e, b, p2, pe);
    let leak_12 = nozzle_flow_kg_s(f * m.c_12, b, p1, p2);
    let ext = nozzle_flow_kg_s(m.c_ext, b, pe, p_atm_pa);
    q1 -= leak_1e + leak_12;
    q2 += leak_12 - leak_2e;
    qe += leak_1e + leak_2e - ext;
    let mut q = [q1, q2, qe];
    for law in &m.laws {
        if let super::laws::Drawn::Leak(l) = law {
            // What leaves one volume enters the other (atmosphere has no balance).
            let f = l.flow_kg_s(p_pa, p_atm_pa);
            if let Some(i) = l.from.index() {
                q[i] -= f;
            }
            if let Some(i) = l.to.index() {
                q[i] += f;
            }
        }
    }
    q
}

/// Loss torque of the motor's friction laws ([`TwinMotor::laws`]), N·m.
pub fn law_friction_nm(m: &TwinMotor, p_pa: [f64; 3], w_rad_s: f64) -> f64 {
    let t_air = air_torque_nm(m, p_pa, w_rad_s);
    m.laws
        .iter()
        .map(|law| match law {
            super::laws::Drawn::Friction(f) => f.torque_nm(p_pa, w_rad_s, t_air, m.w_reg),
            super::laws::Drawn::Leak(_) => 0.0,
        })
        .sum()
}

/// The dry part at rest of the motor's friction laws, N·m.
pub fn law_static_nm(m: &TwinMotor, p_pa: [f64; 3]) -> f64 {
    let t_air = air_torque_nm(m, p_pa, 0.0);
    m.laws
        .iter()
        .map(|law| match law {
            super::laws::Drawn::Friction(f) => f.static_nm(p_pa, t_air),
            super::laws::Drawn::Leak(_) => 0.0,
        })
        .sum()
}

/// Exhaust mass flow V_e → atmosphere through EXT, kg/s.
pub fn exhaust_flow_kg_s(m: &TwinMotor, pe_pa: f64, p_atm_pa: f64) -> f64 {
    nozzle_flow_kg_s(m.c_ext, m.b_crit, pe_pa, p_atm_pa)
}
