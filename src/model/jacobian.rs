//! Analytic Jacobian ∂f/∂x of the base motor model, f = dx/dt of [`Motor::derivatives`].
//!
//! A stiff integrator needs ∂f/∂x at every step; forward differences cost four extra
//! right-hand-side evaluations and carry a truncation error of about √ε. The base model is
//! a sum of closed-form pieces, so its Jacobian follows term by term with the chain rule:
//!
//! ```text
//! f_1 = R·T0/V_1 · (ṁ_port1 − ṁ_1e − ṁ_12 + ṁ_d1)
//! f_2 = R·T0/V_2 · (ṁ_12 − ṁ_port2 − ṁ_2e + ṁ_d2)
//! f_e = R·T0/V_e · (ṁ_1e + ṁ_2e − ṁ_ext + ṁ_de)
//! f_ω = (T(p_1, p_2, p_e, ω) − T_f(ω) − T_load(ω)) / J
//! ```
//!
//! Each nozzle flow depends on its two end pressures only (slopes from
//! [`Nozzle::flow_with_slopes`]), the displacement flows on one filling pressure, p_e and
//! |ω|, the torque linearly on the pressures and through the tanh blend on ω.
//!
//! Catalog effects and discovered terms are not covered: with any of them switched on the
//! functions here return `None` and the caller falls back to finite differences.
//!
//! Units: row i of the Jacobian is in (unit of dx_i/dt) per (unit of x_k), e.g. 1/s for
//! ∂ṗ/∂p, Pa/rad for ∂ṗ/∂ω, rad/(s²·Pa) for ∂ω̇/∂p.

use crate::model::motor::ThrottleSide::{self, AtA, AtB};
use crate::model::motor::{idx, Balance, Boundary, Load, Motor, State, N_STATES};
use crate::model::nozzle::{series_flow, Nozzle};
use crate::model::thermo::{displacement_flows, Cycle, DisplacementFlows};
use crate::units::constants::OMEGA_BLEND_RAD_S;

/// A Jacobian ∂f/∂x, row-major: `j[i][k] = ∂f_i/∂x_k`.
pub type Jacobian = [State; N_STATES];

/// A mass flow and its slopes (ṁ, ∂ṁ/∂p_a, ∂ṁ/∂p_b), kg/s and kg/(s·Pa), as returned by
/// [`Nozzle::flow_with_slopes`] for a flow from `p_a` to `p_b`.
pub(crate) type SlopedFlow = (f64, f64, f64);

/// Flow through two restrictions in series from `p_a` to `p_b` (as `series_flow`) and its
/// slopes (ṁ, ∂ṁ/∂p_a, ∂ṁ/∂p_b).
///
/// The intermediate pressure p_m solves g = ṁ_1(p_a, p_m) − ṁ_2(p_m, p_b) = 0, so by the
/// implicit-function theorem dp_m/dp_a = ∂_a ṁ_1 / D and dp_m/dp_b = −∂_b ṁ_2 / D with
/// D = ∂_m ṁ_2 − ∂_m ṁ_1 > 0 (both nozzles pass more the larger their pressure drop). Then
///
/// ```text
/// ∂ṁ/∂p_a = ∂_a ṁ_1 + ∂_m ṁ_1 · dp_m/dp_a =  ∂_a ṁ_1 · ∂_m ṁ_2 / D
/// ∂ṁ/∂p_b = ∂_b ṁ_2 + ∂_m ṁ_2 · dp_m/dp_b = −∂_b ṁ_2 · ∂_m ṁ_1 / D
/// ```
///
/// Slopes, like the flow, are taken at the p_m the solver returns; a choked first nozzle
/// (∂_m ṁ_1 = 0) makes the flow independent of p_b, as it should. (The model takes all
/// slopes at once from `series_slopes`; this pair is what the tests check against
/// difference quotients.)
#[cfg(test)]
pub fn series_flow_with_slopes(first: &Nozzle, second: &Nozzle, p_a: f64, p_b: f64) -> SlopedFlow {
    let (m, d_a, d_b, _) = series_flow_sensitivities(first, second, p_a, p_b);
    (m, d_a, d_b)
}

/// As `series_flow_with_slopes`, and the slope ∂ṁ/∂ln C_2 of the flow in the logarithm
/// of the second nozzle's conductance, kg/s (how an outlet throttle that moves in time
/// moves the flow).
///
/// ṁ_2 = C_2·ρ0·p_m·ψ(p_b/p_m) is proportional to C_2, so ∂ṁ_2/∂ln C_2 = ṁ; at fixed
/// p_a, p_b the balance g(p_m) = 0 gives dp_m/dln C_2 = −ṁ/D, and
/// ∂ṁ/∂ln C_2 = ∂_m ṁ_1 · dp_m/dln C_2 = −∂_m ṁ_1 · ṁ / D (≥ 0: a wider throttle passes more).
fn series_flow_sensitivities(
    first: &Nozzle,
    second: &Nozzle,
    p_a: f64,
    p_b: f64,
) -> (f64, f64, f64, f64) {
    let (m, d_a, d_b, _, d_ln_c2) = series_slopes(first, second, p_a, p_b);
    (m, d_a, d_b, d_ln_c2)
}

/// As `series_flow_sensitivities`, but the last slope is the one in the logarithm of the
/// FIRST nozzle's conductance, kg/s (a throttle in front of port 1: supply → throttle →
/// duct).
///
/// ṁ_1 ∝ C_1, so ∂ṁ_1/∂ln C_1 = ṁ; at fixed p_a, p_b the balance gives
/// dp_m/dln C_1 = ṁ/D, and ∂ṁ/∂ln C_1 = ∂_m ṁ_2 · dp_m/dln C_1 = ∂_m ṁ_2 · ṁ / D (≥ 0 for a
/// forward flow: a wider throttle passes more).
pub fn series_flow_sensitivities_first(
    first: &Nozzle,
    second: &Nozzle,
    p_a: f64,
    p_b: f64,
) -> (f64, f64, f64, f64) {
    let (m, d_a, d_b, d_ln_c1, _) = series_slopes(first, second, p_a, p_b);
    (m, d_a, d_b, d_ln_c1)
}

/// The series flow ṁ with every slope the two functions above hand out: ∂ṁ/∂p_a, ∂ṁ/∂p_b,
/// ∂ṁ/∂ln C_1, ∂ṁ/∂ln C_2 (D = ∂_m ṁ_2 − ∂_m ṁ_1, the balance's slope in p_m).
fn series_slopes(first: &Nozzle, second: &Nozzle, p_a: f64, p_b: f64) -> (f64, f64, f64, f64, f64) {
    let (m, p_m) = series_flow(first, second, p_a, p_b);
    let (_, d1_a, d1_m) = first.flow_with_slopes(p_a, p_m);
    let (_, d2_m, d2_b) = second.flow_with_slopes(p_m, p_b);
    let den = d2_m - d1_m;
    if den.is_nan() || den <= 0.0 {
        // Only with non-positive pressures, where both nozzles pass nothing.
        return (m, 0.0, 0.0, 0.0, 0.0);
    }
    (
        m,
        d1_a * d2_m / den,
        -d1_m * d2_b / den,
        d2_m * m / den,
        -d1_m * m / den,
    )
}

/// How fast the boundary of a transient moves: the time derivatives of the inputs that
/// [`Motor::time_slope`] needs.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BoundaryRate {
    /// dp_port1/dt, Pa/s (a supply-pressure ramp).
    pub(crate) p_port1_pa_s: f64,
    /// d ln(C_port2)/dt, 1/s (an outlet throttle that opens or closes; 0 without one).
    pub(crate) ln_c_port2_per_s: f64,
}

impl Load {
    /// dT_load/dω at speed ω, N·m·s/rad: c for the viscous brake, 0 for the free shaft and
    /// a constant torque (ω is taken for symmetry with [`Load::torque`]; no load uses it).
    fn torque_slope(&self, _omega: f64) -> f64 {
        match *self {
            Load::ViscousBrake { c_nm_s_rad } | Load::BrakeAndTorque { c_nm_s_rad, .. } => {
                c_nm_s_rad
            }
            Load::None | Load::Torque { .. } => 0.0,
        }
    }
}

/// Adds to the mass-balance rows `g` (kg/s per state unit) the slopes of a flow ṁ from
/// volume `from` to volume `to`, each given by its state index: ṁ leaves one and enters the
/// other, and depends on their two pressures.
fn add_internal_flow(g: &mut Jacobian, from: usize, to: usize, flow: SlopedFlow) {
    let (_, d_from, d_to) = flow;
    g[from][from] -= d_from;
    g[from][to] -= d_to;
    g[to][from] += d_from;
    g[to][to] += d_to;
}

/// Adds `grad` (a gradient over the state) to row `row` of `g`.
fn add_row(g: &mut Jacobian, row: usize, grad: &State, sign: f64) {
    for (gk, dk) in g[row].iter_mut().zip(grad) {
        *gk += sign * dk;
    }
}

/// Displacement flows of the base model (as [`displacement_flows`] with no carry-over) and
/// the gradients over the state of the inlet flow ṁ_in and the outlet flow ṁ_out.
///
/// With k = V_disp/(2π·R·T0): ṁ_in = max(p_fill·|ω|·k, 0) with p_fill = p_1 for ω ≥ 0 and
/// p_2 for ω < 0, ṁ_out = max(p_e·|ω|·ε·k, 0). So ∂ṁ_in/∂p_fill = |ω|·k,
/// ∂ṁ_in/∂ω = sgn(ω)·p_fill·k, ∂ṁ_out/∂p_e = |ω|·ε·k, ∂ṁ_out/∂ω = sgn(ω)·p_e·ε·k, and zero
/// where the clamp holds a flow at 0. At ω = 0 exactly, where |ω| has a kink, the slopes
/// are those of the branch `displacement_flows` takes there (forward, sgn = +1).
fn displacement_with_slopes(cycle: &Cycle, x: &State) -> (DisplacementFlows, State, State) {
    let [p1, p2, pe, omega] = *x;
    let forward = omega >= 0.0;
    let p_fill = if forward { p1 } else { p2 };
    let flows = displacement_flows(cycle, omega, p_fill, pe, 0.0);
    let k = cycle.displacement_k();
    let (speed, sign) = (omega.abs(), if forward { 1.0 } else { -1.0 });
    let mut d_in = [0.0; N_STATES];
    if p_fill * speed * k >= 0.0 {
        d_in[if forward { idx::P1 } else { idx::P2 }] = speed * k;
        d_in[idx::OMEGA] = sign * p_fill * k;
    }
    let mut d_out = [0.0; N_STATES];
    if pe * speed * cycle.eps * k >= 0.0 {
        d_out[idx::PE] = speed * cycle.eps * k;
        d_out[idx::OMEGA] = sign * pe * cycle.eps * k;
    }
    (flows, d_in, d_out)
}

/// Torque of the ideal motor with the forward/reverse blend (as the motor computes it), N·m,
/// and its gradient over the state.
///
/// T = w(ω)·T_fwd(p_1, p_2, p_e) + (1 − w(ω))·T_rev with T_rev = −T_fwd(p_2, p_1, p_e) and
/// w = ½(1 + tanh(ω/ω_b)). The cycle torque is linear and homogeneous in its three
/// pressures, so its gradient (a, b, e) is its value at the unit vectors; then
/// ∂T/∂p_1 = w·a − (1 − w)·b, ∂T/∂p_2 = w·b − (1 − w)·a, ∂T/∂p_e = (2w − 1)·e and
/// ∂T/∂ω = w'(ω)·(T_fwd − T_rev) with w' = ½(1 − tanh²(ω/ω_b))/ω_b.
fn ideal_torque_with_slopes(cycle: &Cycle, x: &State) -> (f64, State) {
    let [p1, p2, pe, omega] = *x;
    // w = forward_weight(ω), written out so that tanh is taken once for w and w'.
    let th = crate::numerics::scalar::tanh(omega / OMEGA_BLEND_RAD_S);
    let w = 0.5 * (1.0 + th);
    let t_fwd = cycle.torque_one_way(p1, p2, pe);
    let t_rev = -cycle.torque_one_way(p2, p1, pe);
    let torque = w * t_fwd + (1.0 - w) * t_rev;
    let [a, b, e] = cycle.unit_torques();
    let dw = 0.5 * (1.0 - th * th) / OMEGA_BLEND_RAD_S;
    let grad = [
        w * a - (1.0 - w) * b,
        w * b - (1.0 - w) * a,
        (2.0 * w - 1.0) * e,
        dw * (t_fwd - t_rev),
    ];
    (torque, grad)
}

impl Motor {
    /// ∂(dx/dt)/∂x at state `x` under `bc`, row-major: `j[i][k] = ∂f_i/∂x_k` with
    /// f = [`Motor::derivatives`] and x = [p_1 (Pa), p_2 (Pa), p_e (Pa), ω (rad/s)].
    ///
    /// `None` when the motor has catalog effects switched on or discovered extra terms
    /// (callers then use finite differences). At the kinks of the model (ω = 0, a nozzle at
    /// its laminar threshold r = 0.999) it returns one of the one-sided slopes.
    pub fn jacobian(&self, x: &State, bc: &Boundary) -> Option<Jacobian> {
        self.derivatives_and_jacobian(x, bc).map(|(_, j)| j)
    }

    /// dx/dt (bit for bit what [`Motor::derivatives`] returns) and ∂(dx/dt)/∂x together,
    /// sharing the flow evaluations; `None` under the same conditions as [`Motor::jacobian`].
    ///
    /// Rows: ∂f_i/∂x = R·T0/V_i · ∂(Σṁ_i)/∂x for the three volumes and
    /// ∂f_ω/∂x = ∂(T − T_f − T_load)/∂x / J.
    pub fn derivatives_and_jacobian(&self, x: &State, bc: &Boundary) -> Option<(State, Jacobian)> {
        self.linearise(x, bc).map(|(f, j, _)| (f, j))
    }

    /// dx/dt, ∂(dx/dt)/∂x (as [`Motor::derivatives_and_jacobian`]) and ∂(dx/dt)/∂t (as
    /// [`Motor::time_slope`]) together, sharing the port flows' slopes: what a stiff
    /// integrator asks for at every step of a transient.
    pub fn derivatives_jacobian_and_time_slope(
        &self,
        x: &State,
        bc: &Boundary,
        rate: &BoundaryRate,
    ) -> Option<(State, Jacobian, State)> {
        let (f, j, inputs) = self.linearise(x, bc)?;
        Some((f, j, self.time_slope_from(&inputs, rate)))
    }

    /// dx/dt, ∂(dx/dt)/∂x and the port flows' slopes in the boundary's moving inputs
    /// (∂ṁ_port1/∂p_port1, kg/(s·Pa); ∂ṁ_port2/∂ln C_port2, kg/s).
    ///
    /// Rows: ∂f_i/∂x = R·T0/V_i · ∂(Σṁ_i)/∂x for the three volumes and
    /// ∂f_ω/∂x = ∂(T − T_f − T_load)/∂x / J.
    fn linearise(&self, x: &State, bc: &Boundary) -> Option<(State, Jacobian, [f64; 2])> {
        if !self.effects.is_empty() || !self.extra.is_empty() {
            return None;
        }
        let (mut b, mut g, inputs) = self.flows_with_slopes(x, bc);
        self.torques_with_slopes(x, bc, &mut b, &mut g);
        let p = self.params();
        let [s1, s2, se] = self.rt_over_vol();
        let scale = [s1, s2, se, 1.0 / p.inertia()];
        for (row, s) in g.iter_mut().zip(scale) {
            row.iter_mut().for_each(|v| *v *= s);
        }
        Some((self.derivatives_from(&b), g, inputs))
    }

    /// ∂(dx/dt)/∂t at state `x` under `bc` whose inputs move at `rate`: the model depends on
    /// time only through its boundary, so
    ///
    /// ```text
    /// ∂f_1/∂t = R·T0/V_1 · ∂ṁ_port1/∂p_port1 · dp_port1/dt
    /// ∂f_2/∂t = −R·T0/V_2 · ∂ṁ_port2/∂ln C_port2 · d ln C_port2/dt
    /// ∂f_e/∂t = ∂f_ω/∂t = 0
    /// ```
    ///
    /// (units of dx/dt per second). A stiff integrator takes this instead of a forward
    /// difference in time, which costs one more right-hand side per step.
    /// `None` under the same conditions as [`Motor::jacobian`] (effects or extra terms).
    pub fn time_slope(&self, x: &State, bc: &Boundary, rate: &BoundaryRate) -> Option<State> {
        if !self.effects.is_empty() || !self.extra.is_empty() {
            return None;
        }
        let p = self.params();
        let (_, d_supply, _, _) = self.port_flow_with_slopes(
            p.c_in1(),
            bc.c_port1_m3_s_pa,
            AtA,
            bc.p_port1_pa,
            x[idx::P1],
        );
        let (_, _, _, d_ln_c) = self.port_flow_with_slopes(
            p.c_out2(),
            bc.c_port2_m3_s_pa,
            AtB,
            x[idx::P2],
            bc.p_port2_pa,
        );
        Some(self.time_slope_from(&[d_supply, d_ln_c], rate))
    }

    /// ∂(dx/dt)/∂t from the port flows' slopes in the moving inputs (see
    /// [`Motor::time_slope`]).
    fn time_slope_from(&self, [d_supply, d_ln_c]: &[f64; 2], rate: &BoundaryRate) -> State {
        let [s1, s2, _] = self.rt_over_vol();
        let mut f_t = [0.0; N_STATES];
        // −(R·T0/V_2) is exactly (−R·T0)/V_2: negation commutes with rounding.
        f_t[idx::P1] = s1 * d_supply * rate.p_port1_pa_s;
        f_t[idx::P2] = -s2 * d_ln_c * rate.ln_c_port2_per_s;
        f_t
    }

    /// A nozzle of conductance `c` with the motor's critical ratio (as the motor builds it).
    fn sloped_nozzle(&self, c: f64) -> Nozzle {
        Nozzle::new(c, self.params().b_crit())
    }

    /// [`Motor::port_flow`] with its slopes (ṁ, ∂ṁ/∂p_a, ∂ṁ/∂p_b, ∂ṁ/∂ln C_throttle; the
    /// last 0 without a throttle): the same nozzles in the same order.
    fn port_flow_with_slopes(
        &self,
        c_duct: f64,
        c_thr: Option<f64>,
        side: ThrottleSide,
        p_a: f64,
        p_b: f64,
    ) -> (f64, f64, f64, f64) {
        let duct = self.sloped_nozzle(c_duct);
        match (c_thr, side) {
            (None, _) => {
                let (m, d_a, d_b) = duct.flow_with_slopes(p_a, p_b);
                (m, d_a, d_b, 0.0)
            }
            (Some(c), ThrottleSide::AtA) => {
                series_flow_sensitivities_first(&self.sloped_nozzle(c), &duct, p_a, p_b)
            }
            (Some(c), ThrottleSide::AtB) => {
                series_flow_sensitivities(&duct, &self.sloped_nozzle(c), p_a, p_b)
            }
        }
    }

    /// Every mass flow of [`Motor::balance`] (base model) and the gradients of the net mass
    /// flows dm_1, dm_2, dm_e (rows P1, P2, PE of the result; row OMEGA left zero), kg/s
    /// per state unit; and the port flows' slopes in the moving inputs
    /// (∂ṁ_port1/∂p_port1, ∂ṁ_port2/∂ln C_port2).
    fn flows_with_slopes(&self, x: &State, bc: &Boundary) -> (Balance, Jacobian, [f64; 2]) {
        use idx::{P1, P2, PE};
        let p = self.params();
        let [p1, p2, pe, _] = *x;
        let port1 =
            self.port_flow_with_slopes(p.c_in1(), bc.c_port1_m3_s_pa, AtA, bc.p_port1_pa, p1);
        let port2 =
            self.port_flow_with_slopes(p.c_out2(), bc.c_port2_m3_s_pa, AtB, p2, bc.p_port2_pa);
        let exhaust = self
            .sloped_nozzle(p.c_ext())
            .flow_with_slopes(pe, bc.p_atm_pa);
        let leak_1e = self.sloped_nozzle(p.c_1e()).flow_with_slopes(p1, pe);
        let leak_2e = self.sloped_nozzle(p.c_2e()).flow_with_slopes(p2, pe);
        let leak_12 = self.sloped_nozzle(p.c_12()).flow_with_slopes(p1, p2);
        let (displacement, d_in, d_out) = displacement_with_slopes(self.cycle(), x);

        let mut g = [[0.0; N_STATES]; N_STATES];
        // Port flows enter V_1 / leave V_2 / leave V_e; the far side is a boundary.
        g[P1][P1] += port1.2;
        g[P2][P2] -= port2.1;
        g[PE][PE] -= exhaust.1;
        add_internal_flow(&mut g, P1, PE, leak_1e);
        add_internal_flow(&mut g, P2, PE, leak_2e);
        add_internal_flow(&mut g, P1, P2, leak_12);
        // ṁ_in leaves the inlet side, ṁ_out enters the discharge side, V_e takes the rest.
        let (inlet, outlet) = if x[idx::OMEGA] >= 0.0 {
            (P1, P2)
        } else {
            (P2, P1)
        };
        add_row(&mut g, inlet, &d_in, -1.0);
        add_row(&mut g, outlet, &d_out, 1.0);
        add_row(&mut g, PE, &d_in, 1.0);
        add_row(&mut g, PE, &d_out, -1.0);

        let b = Balance {
            flow_port1_kg_s: port1.0,
            flow_port2_kg_s: port2.0,
            flow_exhaust_kg_s: exhaust.0,
            leak_1e_kg_s: leak_1e.0,
            leak_2e_kg_s: leak_2e.0,
            leak_12_kg_s: leak_12.0,
            displacement,
            // Same operation order as `Motor::balance`, so dx/dt agrees bit for bit.
            dm1_kg_s: port1.0 - leak_1e.0 - leak_12.0 + displacement.into_1_kg_s,
            dm2_kg_s: leak_12.0 - port2.0 - leak_2e.0 + displacement.into_2_kg_s,
            dme_kg_s: leak_1e.0 + leak_2e.0 - exhaust.0 + displacement.into_e_kg_s,
            ..Balance::default()
        };
        (b, g, [port1.1, port2.3])
    }

    /// Fills the torques of `b` (base model) and row OMEGA of `g` with the gradient of
    /// T − T_f − T_load, N·m per state unit. T_f = T_c·tanh(ω/ω_reg) + d·ω, so
    /// dT_f/dω = T_c·(1 − tanh²(ω/ω_reg))/ω_reg + d.
    fn torques_with_slopes(&self, x: &State, bc: &Boundary, b: &mut Balance, g: &mut Jacobian) {
        let p = self.params();
        let omega = x[idx::OMEGA];
        let (torque, mut grad) = ideal_torque_with_slopes(self.cycle(), x);
        b.torque_ideal_nm = torque;
        let th = crate::numerics::scalar::tanh(omega / p.w_reg());
        // The base model's friction_torque(ω) = T_c·tanh(ω/ω_reg) + d·ω, with tanh taken once.
        b.torque_friction_nm = p.t_coulomb() * th + p.visc() * omega;
        b.torque_load_nm = bc.load.torque(omega);
        let d_friction = p.t_coulomb() * (1.0 - th * th) / p.w_reg() + p.visc();
        grad[idx::OMEGA] -= d_friction + bc.load.torque_slope(omega);
        g[idx::OMEGA] = grad;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::effects::{Effect, EffectSet};
    use crate::model::extra::{BalanceId, ExtraTerm, PressureFactor, SpeedFactor};
    use crate::model::params::MotorParams;
    use crate::units::constants::P_ATM_PA;

    /// Typical magnitude of each state's rate: rows are compared in units of
    /// (scale of f_i)/(unit of x_k), so that a column mixes Pa/s and rad/s² fairly.
    const ROW_SCALE: State = [1e5, 1e5, 1e5, 1e3];

    /// Central differences of `Motor::derivatives`. Pressure steps are 1e-6 of the pressure
    /// (0.1–0.7 Pa): truncation stays small even next to the laminar threshold, where ψ
    /// curves most, while rounding in the ~1e8 Pa/s rates stays below 1e-7 of the slopes
    /// (1e-5 and 1e-7 both give larger errors). Speed steps are 1e-4 of max(|ω|, 1 rad/s),
    /// large enough that rounding does not swamp ∂ṗ/∂ω near standstill and small against
    /// the blend and friction speeds (1 and ≥ 0.2 rad/s) and the distance to ω = 0.
    fn central_differences(m: &Motor, x: &State, bc: &Boundary) -> Jacobian {
        let mut j = [[0.0; N_STATES]; N_STATES];
        for k in 0..N_STATES {
            let h = if k == idx::OMEGA {
                1e-4 * x[k].abs().max(1.0)
            } else {
                1e-6 * x[k].abs().max(1e4)
            };
            let (mut up, mut down) = (*x, *x);
            up[k] += h;
            down[k] -= h;
            let (fu, fd) = (m.derivatives(&up, bc), m.derivatives(&down, bc));
            for i in 0..N_STATES {
                j[i][k] = (fu[i] - fd[i]) / (up[k] - down[k]);
            }
        }
        j
    }

    /// Asserts the analytic Jacobian equals central differences to 1e-5 of each column's
    /// scale (after dividing row i by ROW_SCALE[i]), and dx/dt bit for bit. Returns the
    /// largest error found, relative to its column scale.
    fn check(m: &Motor, x: &State, bc: &Boundary) -> f64 {
        let (f, j) = m.derivatives_and_jacobian(x, bc).expect("base model");
        assert_eq!(f, m.derivatives(x, bc), "dx/dt at {x:?}");
        let fd = central_differences(m, x, bc);
        let mut worst: f64 = 0.0;
        for k in 0..N_STATES {
            let col_scale = (0..N_STATES)
                .map(|i| fd[i][k].abs().max(j[i][k].abs()) / ROW_SCALE[i])
                .fold(1e-300, f64::max);
            for i in 0..N_STATES {
                let err = (j[i][k] - fd[i][k]).abs() / ROW_SCALE[i];
                assert!(
                    err <= 1e-5 * col_scale,
                    "x {x:?} bc {bc:?}\n∂f{i}/∂x{k}: analytic {:e} vs fd {:e} (rel {:e})",
                    j[i][k],
                    fd[i][k],
                    err / col_scale
                );
                worst = worst.max(err / col_scale);
            }
        }
        worst
    }

    /// Forward, reverse, choked, subsonic, laminar, near standstill (both signs) and
    /// sub-atmospheric states; none sits on a kink.
    const STATES: [State; 14] = [
        [6e5, 1.5e5, 1.3e5, 800.0],
        [3e5, 1.4e5, 1.2e5, 500.0],
        [3e5, 4e5, 2e5, -300.0],
        [1.5e5, 6.5e5, 1.25e5, -900.0],
        [5e5, 2e5, 1.2e5, 0.05],
        [5e5, 2e5, 1.2e5, -0.05],
        [2e5, 3e5, 1.1e5, 0.3],
        [2e5, 1.8e5, 1.1e5, -2.0],
        [7.2995e5, 1.0135e5, 1.01335e5, 50.0],
        [1.0137e5, 7.2993e5, 1.01345e5, -40.0],
        [4e5, 3.9995e5, 3.9991e5, 10.0],
        [2e5, 0.9e5, 0.95e5, 100.0],
        [7.0e5, 6.9e5, 1.5e5, 1.5],
        [1.2e5, 1.1e5, 1.05e5, -0.7],
    ];

    fn boundaries() -> Vec<Boundary> {
        let fwd = Boundary::supplied(7.3e5, P_ATM_PA, Load::None);
        let rev = Boundary {
            p_port1_pa: P_ATM_PA,
            p_port2_pa: 7.3e5,
            ..fwd
        };
        let brake = Load::ViscousBrake { c_nm_s_rad: 2e-4 };
        let mut out = vec![fwd, rev];
        for c in [1e-9, 1e-8, 1e-7] {
            out.push(Boundary {
                c_port2_m3_s_pa: Some(c),
                load: brake,
                ..fwd
            });
            out.push(Boundary {
                c_port2_m3_s_pa: Some(c),
                ..rev
            });
            // A throttle in front of port 1: supply side forward, exhaust side reversed.
            out.push(Boundary {
                c_port1_m3_s_pa: Some(c),
                load: brake,
                ..fwd
            });
            out.push(Boundary {
                c_port1_m3_s_pa: Some(c),
                ..rev
            });
        }
        out.push(Boundary {
            c_port1_m3_s_pa: Some(3e-9),
            c_port2_m3_s_pa: Some(2e-8),
            load: Load::Torque { t_nm: 0.1 },
            ..fwd
        });
        out.push(Boundary { load: brake, ..rev });
        out
    }

    fn motors() -> Vec<Motor> {
        let d = MotorParams::default();
        let changed = [
            ("c_12", 3e-9),
            ("c_1e", 0.0),
            ("c_ext", 3e-9),
            ("b_crit", 0.3),
            ("eps", 1.3),
            ("n_poly", 1.0),
            ("w_reg", 1.5),
            ("visc", 3e-4),
            ("v_dead", 0.5e-6),
            ("vol2", 7e-6),
            ("inertia", 3e-5),
        ];
        let mut out = vec![Motor::default_motor()];
        for (name, v) in changed {
            let p = d.with(name, v).unwrap();
            out.push(Motor::new(p, EffectSet::empty()));
        }
        let several = d
            .with("b_crit", 0.45)
            .and_then(|p| p.with("z", 7.0))
            .and_then(|p| p.with("c_in1", 2e-8))
            .and_then(|p| p.with("t_coulomb", 0.1))
            .unwrap();
        out.push(Motor::new(several, EffectSet::empty()));
        out
    }

    #[test]
    fn jacobian_matches_central_differences() {
        let mut worst: f64 = 0.0;
        for m in motors() {
            for bc in boundaries() {
                for x in STATES {
                    worst = worst.max(check(&m, &x, &bc));
                }
            }
        }
        println!("largest error: {worst:.2e} of the column scale");
    }

    #[test]
    fn series_slopes_match_central_differences() {
        // Both orders (duct then throttle behind port 2, throttle then duct in front of
        // port 1), both flow directions, and the slopes in ln C of either nozzle.
        let duct_c = 6.758e-9;
        for c in [1e-9, 5e-9, 3e-8, 1e-7] {
            for throttle_first in [false, true] {
                let pair = |c_thr: f64, c_duct: f64| {
                    let (thr, duct) = (Nozzle::new(c_thr, 0.5), Nozzle::new(c_duct, 0.5));
                    if throttle_first {
                        (thr, duct)
                    } else {
                        (duct, thr)
                    }
                };
                let (first, second) = pair(c, duct_c);
                for (pa, pb) in [
                    (7e5, 1.0e5),
                    (3e5, 2.5e5),
                    (2e5, 1.9995e5),
                    (1.2e5, 6e5),
                    (1.0e5, 1.00005e5),
                ] {
                    let (m, da, db) = series_flow_with_slopes(&first, &second, pa, pb);
                    assert_eq!(m, series_flow(&first, &second, pa, pb).0);
                    let h = 1e-6 * pa.max(pb);
                    let f = |a: f64, b: f64| series_flow(&first, &second, a, b).0;
                    let fd_a = (f(pa + h, pb) - f(pa - h, pb)) / (2.0 * h);
                    let fd_b = (f(pa, pb + h) - f(pa, pb - h)) / (2.0 * h);
                    let scale = fd_a.abs().max(fd_b.abs());
                    let at = format!("{c:e} first {throttle_first} {pa} {pb}");
                    assert!((da - fd_a).abs() <= 1e-5 * scale, "{at}: {da} vs {fd_a}");
                    assert!((db - fd_b).abs() <= 1e-5 * scale, "{at}: {db} vs {fd_b}");
                    // ∂ṁ/∂ln C of the throttle, wherever it sits.
                    let k: f64 = 1e-6;
                    let moved = |s: f64| {
                        let (f1, f2) = pair(c * s, duct_c);
                        series_flow(&f1, &f2, pa, pb).0
                    };
                    let fd_c = (moved(k.exp()) - moved((-k).exp())) / (2.0 * k);
                    let d_c = if throttle_first {
                        series_flow_sensitivities_first(&first, &second, pa, pb).3
                    } else {
                        series_flow_sensitivities(&first, &second, pa, pb).3
                    };
                    assert!(
                        (d_c - fd_c).abs() <= 1e-5 * m.abs().max(fd_c.abs()),
                        "{at}: d/dlnC {d_c} vs {fd_c}"
                    );
                }
            }
        }
    }

    #[test]
    fn time_slope_matches_central_differences_in_the_inputs() {
        // f depends on t only through p_port1 and C_port2: move them at the given rates.
        let rate = BoundaryRate {
            p_port1_pa_s: 1.2e4,
            ln_c_port2_per_s: -0.08,
        };
        let h = 1e-3;
        for m in motors() {
            for bc in boundaries() {
                let at = |dt: f64| Boundary {
                    p_port1_pa: bc.p_port1_pa + rate.p_port1_pa_s * dt,
                    c_port2_m3_s_pa: bc
                        .c_port2_m3_s_pa
                        .map(|c| c * (rate.ln_c_port2_per_s * dt).exp()),
                    ..bc
                };
                for x in STATES {
                    let f_t = m.time_slope(&x, &bc, &rate).unwrap();
                    let (up, down) = (m.derivatives(&x, &at(h)), m.derivatives(&x, &at(-h)));
                    for i in 0..N_STATES {
                        let fd = (up[i] - down[i]) / (2.0 * h);
                        let scale = ROW_SCALE[i] * 1e-3;
                        assert!(
                            (f_t[i] - fd).abs() <= 1e-5 * fd.abs().max(scale),
                            "x {x:?} bc {bc:?} row {i}: {} vs {fd}",
                            f_t[i]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn standstill_gives_the_forward_one_sided_slope() {
        let m = Motor::default_motor();
        let bc = Boundary::supplied(7.3e5, P_ATM_PA, Load::None);
        let x = [5e5, 2e5, 1.2e5, 0.0];
        let j = m.jacobian(&x, &bc).unwrap();
        let h = 1e-4;
        let up = [x[0], x[1], x[2], h];
        let right = (m.derivatives(&up, &bc)[idx::P1] - m.derivatives(&x, &bc)[idx::P1]) / h;
        assert!((j[idx::P1][idx::OMEGA] - right).abs() <= 1e-5 * right.abs());
    }

    #[test]
    fn effects_and_extra_terms_give_none() {
        let bc = Boundary::supplied(7.3e5, P_ATM_PA, Load::None);
        let x = STATES[0];
        for e in Effect::ALL {
            let m = Motor::new(MotorParams::default(), EffectSet::empty().with(e));
            assert!(m.jacobian(&x, &bc).is_none(), "{}", e.id());
            assert!(m.derivatives_and_jacobian(&x, &bc).is_none());
        }
        let term = ExtraTerm {
            balance: BalanceId::Torque,
            pressure: PressureFactor::P1,
            speed: SpeedFactor::Omega,
            coefficient: 1e-12,
        };
        let m = Motor::default_motor().with_extra(&[term]);
        assert!(m.jacobian(&x, &bc).is_none());
        assert!(Motor::default_motor().jacobian(&x, &bc).is_some());
    }

    /// Mean time per call of `f`, ns, over the test states (after a warm-up pass).
    fn time_per_call(n: usize, mut f: impl FnMut(&State) -> f64) -> f64 {
        use std::hint::black_box;
        let mut sink = 0.0;
        for x in &STATES {
            sink += f(x);
        }
        let t = std::time::Instant::now();
        for i in 0..n {
            sink += f(black_box(&STATES[i % STATES.len()]));
        }
        black_box(sink);
        t.elapsed().as_secs_f64() * 1e9 / n as f64
    }

    /// Cost of `jacobian` and `derivatives_and_jacobian` against one `derivatives` call.
    /// A forward-difference Jacobian costs 4 `derivatives` calls on top of f itself. Run
    /// alone: `cargo test --release --lib timing -- --ignored --nocapture --test-threads=1`.
    #[test]
    #[ignore]
    fn timing_jacobian_versus_derivatives() {
        use std::hint::black_box;
        let m = Motor::default_motor();
        let n = 2_000_000;
        for bc in [boundaries()[0], boundaries()[2]] {
            let bc = black_box(bc);
            let t_f = time_per_call(n, |x| m.derivatives(x, &bc)[0]);
            let t_j = time_per_call(n, |x| m.jacobian(x, &bc).unwrap()[0][0]);
            let t_fj = time_per_call(n, |x| m.derivatives_and_jacobian(x, &bc).unwrap().1[0][0]);
            println!(
                "throttle {:?}: derivatives {t_f:.1} ns; jacobian {t_j:.1} ns ({:.2}×); \
                 derivatives_and_jacobian {t_fj:.1} ns ({:.2}×); forward differences 4×",
                bc.c_port2_m3_s_pa,
                t_j / t_f,
                t_fj / t_f
            );
        }
    }
}
