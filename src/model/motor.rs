//! The motor model: parameters → state derivatives (docs/model.md; paper Figs. 7 and 8).
//!
//! State x = [p_1, p_2, p_e, ω]: the pressures (Pa) of the three isothermal lumped volumes
//! at the stator inlets and the rotor speed (rad/s). Pressures are states rather than masses
//! because they are better scaled for the integrator; with constant volume and temperature
//! dm/dt = Σṁ is the same equation as dp/dt = R·T0/V · Σṁ (paper eqs. 14–15).
//!
//! Flow paths (ISO 6358 nozzles, `nozzle`):
//! port 1 → in_1 → V_1; V_2 → out_2 → port 2; V_e → EXT → atmosphere;
//! leakage V_1 → V_e (1_Ext), V_2 → V_e (2_Ext), V_1 → V_2 (1_2);
//! plus the displacement flows of the ideal motor (`thermo`).
//! Mechanics: J·dω/dt = T − T_f(ω) − T_load(ω) (docs/model.md, "Mechanics and friction").

use crate::model::effects::{CatalogEffect, Effect, EffectSet, SupplyValve};
// The catalog's hooks, named in the documentation (the code calls them through CatalogEffect).
#[cfg(doc)]
use crate::model::effects::Term;
use crate::model::extra::slot;
pub use crate::model::extra::{
    BalanceId, Chamber, ExtraTerm, LeakPath, PressureFactor, SpeedFactor,
};
use crate::model::nozzle::{series_flow, Nozzle, PreparedNozzle, R_LAMINAR};
use crate::model::params::MotorParams;
use crate::model::thermo::{displacement_flows, forward_weight, Cycle, DisplacementFlows};
use crate::numerics::ode::N_KINKS;
use crate::units::constants::RT0;

/// Number of ODE states, and the state vector [p_1 (Pa), p_2 (Pa), p_e (Pa), ω (rad/s)].
pub use crate::numerics::ode::{State, N_STATES};

/// Index of each state in [`State`].
pub mod idx {
    /// p_1, Pa.
    pub const P1: usize = 0;
    /// p_2, Pa.
    pub const P2: usize = 1;
    /// p_e, Pa.
    pub const PE: usize = 2;
    /// ω, rad/s.
    pub const OMEGA: usize = 3;
}

/// Mechanical load on the shaft.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[non_exhaustive]
pub enum Load {
    /// Free shaft.
    #[default]
    None,
    /// Eddy-current brake: T_load = c·ω (c in N·m·s/rad).
    ViscousBrake {
        /// Brake coefficient c, N·m·s/rad.
        c_nm_s_rad: f64,
    },
    /// Constant torque opposing forward rotation, N·m (an active load).
    Torque {
        /// The torque, N·m.
        t_nm: f64,
    },
    /// Eddy-current brake and a constant torque together: T_load = c·ω + t (the load of
    /// an exported FMU, whose user sets both).
    BrakeAndTorque {
        /// Brake coefficient c, N·m·s/rad.
        c_nm_s_rad: f64,
        /// The constant torque t, N·m.
        t_nm: f64,
    },
}

impl Load {
    /// Load torque at speed ω, N·m.
    pub fn torque(&self, omega: f64) -> f64 {
        match *self {
            Load::None => 0.0,
            Load::ViscousBrake { c_nm_s_rad } => c_nm_s_rad * omega,
            Load::Torque { t_nm } => t_nm,
            Load::BrakeAndTorque { c_nm_s_rad, t_nm } => c_nm_s_rad * omega + t_nm,
        }
    }
}

/// What the surroundings impose on the motor at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Boundary {
    /// Absolute pressure upstream of port 1, Pa (supply, or atmosphere when reversed).
    pub p_port1_pa: f64,
    /// Absolute pressure downstream of port 2, Pa (atmosphere, or supply when reversed).
    pub p_port2_pa: f64,
    /// Atmosphere that the exhaust port discharges to, Pa.
    pub p_atm_pa: f64,
    /// Extra nozzle in series in front of port 1 (inlet throttling), m³/(s·Pa).
    pub c_port1_m3_s_pa: Option<f64>,
    /// Extra nozzle in series behind port 2 (outlet throttling), m³/(s·Pa).
    pub c_port2_m3_s_pa: Option<f64>,
    /// Mechanical load on the shaft.
    pub load: Load,
}

impl Boundary {
    /// Supply at port 1, port 2 and exhaust to atmosphere.
    pub fn supplied(p_supply_pa: f64, p_atm_pa: f64, load: Load) -> Self {
        Self {
            p_port1_pa: p_supply_pa,
            p_port2_pa: p_atm_pa,
            p_atm_pa,
            c_port1_m3_s_pa: None,
            c_port2_m3_s_pa: None,
            load,
        }
    }
}

/// At which end of a port's line its throttle sits, for a flow counted from `p_a` to `p_b`
/// ([`Motor::port_flow`]). A throttle is fitted outside the motor, so in front of port 1
/// (supply → throttle → in_1 → V_1, port 1's flow counted from the supply) it is at the `p_a`
/// end, and behind port 2 (V_2 → out_2 → throttle → atmosphere, counted from V_2) at the
/// `p_b` end. The order is physical: a reversed flow passes the same elements backwards.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThrottleSide {
    /// p_a → throttle → duct → p_b.
    AtA,
    /// p_a → duct → throttle → p_b.
    AtB,
}

/// Every flow and torque at one state: the balances behind the derivatives.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Balance {
    /// Mass flow into the motor at port 1, kg/s.
    pub flow_port1_kg_s: f64,
    /// Mass flow out of the motor at port 2, kg/s.
    pub flow_port2_kg_s: f64,
    /// Mass flow out of the exhaust port, kg/s.
    pub flow_exhaust_kg_s: f64,
    /// Leakage V_1 → V_e, kg/s.
    pub(crate) leak_1e_kg_s: f64,
    /// Leakage V_2 → V_e, kg/s.
    pub(crate) leak_2e_kg_s: f64,
    /// Leakage V_1 → V_2, kg/s.
    pub(crate) leak_12_kg_s: f64,
    /// Displacement flows of the ideal motor (paper eqs. 16–18).
    pub displacement: DisplacementFlows,
    /// Net mass flow into V_1, kg/s.
    pub dm1_kg_s: f64,
    /// Net mass flow into V_2, kg/s.
    pub dm2_kg_s: f64,
    /// Net mass flow into V_e, kg/s.
    pub dme_kg_s: f64,
    /// Torque of the ideal motor, N·m.
    pub torque_ideal_nm: f64,
    /// Friction torque (all friction terms), N·m.
    pub(crate) torque_friction_nm: f64,
    /// Load torque, N·m.
    pub(crate) torque_load_nm: f64,
}

impl Balance {
    /// Shaft torque T − T_f, N·m: what a brake measures at steady speed.
    pub fn torque_shaft_nm(&self) -> f64 {
        self.torque_ideal_nm - self.torque_friction_nm
    }
}

/// A motor model: checked parameters plus the effects switched on.
#[derive(Debug, Clone)]
pub struct Motor {
    /// Checked parameters, SI (read through [`Motor::params`]): private because
    /// [`Motor::new`] derives the cycle, the volumes' R·T0/V and the prepared nozzles from
    /// them once, so a motor with other parameters is a new `Motor`.
    params: MotorParams,
    /// The catalog effects switched on.
    pub effects: EffectSet,
    /// Terms found by `vanefit diagnose` outside the catalog (empty: the model as specified).
    pub extra: Vec<ExtraTerm>,
    cycle: Cycle,
    /// R·T0/V_1, R·T0/V_2, R·T0/V_e, Pa/kg: each volume's pressure rise per kilogram
    /// (paper eqs. 14–15), computed once. The right-hand side and the linearisation
    /// divided by the volumes on every call for values the parameters fix.
    rt_over_vol: [f64; 3],
    /// The base model's six nozzles (C·ρ0 and 1 − b formed once; the same flows as
    /// [`Nozzle::flow`]).
    nozzles: BaseNozzles,
}

/// The base model's nozzles, prepared by [`Motor::new`]: the ducts in_1 and out_2, the
/// exhaust and the three leakage paths.
#[derive(Debug, Clone, Copy)]
struct BaseNozzles {
    in1: PreparedNozzle,
    out2: PreparedNozzle,
    ext: PreparedNozzle,
    leak_1e: PreparedNozzle,
    leak_2e: PreparedNozzle,
    leak_12: PreparedNozzle,
}

impl Motor {
    /// A motor of these parameters with these effects switched on.
    pub fn new(params: MotorParams, effects: EffectSet) -> Self {
        let cycle = Cycle::new(
            params.z().round(),
            params.v_disp() / params.z().round(),
            params.v_dead(),
            params.eps(),
            params.n_poly(),
        );
        let rt_over_vol = [
            RT0 / params.vol1(),
            RT0 / params.vol2(),
            RT0 / params.vole(),
        ];
        let prepared = |c: f64| PreparedNozzle::new(&Nozzle::new(c, params.b_crit()));
        let nozzles = BaseNozzles {
            in1: prepared(params.c_in1()),
            out2: prepared(params.c_out2()),
            ext: prepared(params.c_ext()),
            leak_1e: prepared(params.c_1e()),
            leak_2e: prepared(params.c_2e()),
            leak_12: prepared(params.c_12()),
        };
        Self {
            params,
            effects,
            extra: Vec::new(),
            cycle,
            rt_over_vol,
            nozzles,
        }
    }

    /// The checked parameters, SI.
    pub fn params(&self) -> &MotorParams {
        &self.params
    }

    /// The same motor with discovered terms added to its balances.
    pub fn with_extra(mut self, terms: &[ExtraTerm]) -> Self {
        self.extra.extend_from_slice(terms);
        self
    }

    /// The base model with default parameters (motor AR034-11).
    pub fn default_motor() -> Self {
        Self::new(MotorParams::default(), EffectSet::empty())
    }

    /// The ideal motor's polytropic cycle (docs/model.md, "Cycle work and torque").
    pub fn cycle(&self) -> &Cycle {
        &self.cycle
    }

    /// R·T0/V_i of the three volumes (V_1, V_2, V_e), Pa/kg, as [`Motor::new`] computed them.
    pub(crate) fn rt_over_vol(&self) -> [f64; 3] {
        self.rt_over_vol
    }

    fn nozzle(&self, c: f64) -> Nozzle {
        Nozzle::new(c, self.params.b_crit())
    }

    /// The effects switched on, each with its own parameter values, in registry order.
    /// (Every caller asks [`EffectSet::is_empty`] first and answers the base model directly:
    /// the iterators over an empty set were ~2 % of an evaluation's instructions.)
    fn active(&self) -> impl Iterator<Item = (&'static dyn CatalogEffect, &[f64])> + '_ {
        self.effects
            .iter()
            .map(|e| (e.model(), self.params.effect_values(e)))
    }

    /// Leakage conductance multiplier: the product of the effects' [`Term::leak_factor`]s
    /// (`speed_dependent_leakage`), 1 in the base model.
    fn leak_factor(&self, omega: f64) -> f64 {
        if self.effects.is_empty() {
            return 1.0;
        }
        let factors = self
            .active()
            .filter_map(|(m, own)| m.leak_factor(own, omega));
        factors.reduce(|a, f| a * f).unwrap_or(1.0)
    }

    /// Pressure a compartment is filled to: p_inlet through every effect's
    /// [`Term::filling_pressure`] (`incomplete_filling`); p_inlet in the base model.
    fn filling_pressure(&self, p_inlet: f64, p_e: f64, omega: f64) -> f64 {
        if self.effects.is_empty() {
            return p_inlet;
        }
        self.active().fold(p_inlet, |p, (m, own)| {
            m.filling_pressure(own, p, p_e, omega)
        })
    }

    /// Mass carried back to the inlet side, kg/s: the sum of the effects'
    /// [`Term::carryover_kg_s`] (`dead_volume_carryover`), 0 in the base model.
    fn carryover(&self, p_discharge: f64, omega: f64) -> f64 {
        if self.effects.is_empty() {
            return 0.0;
        }
        let vanes = self.cycle.vanes;
        let flows = self
            .active()
            .filter_map(|(m, own)| m.carryover_kg_s(own, p_discharge, omega, vanes));
        flows.reduce(|a, f| a + f).unwrap_or(0.0)
    }

    /// All friction torques at speed ω, N·m (base Coulomb + viscous, or the effects).
    #[inline(always)]
    pub fn friction_torque(&self, omega: f64, p_inlet: f64, p_e: f64) -> f64 {
        let p = &self.params;
        let (dry, wet) = self.friction_parts(omega, p_inlet, p_e);
        dry * crate::numerics::scalar::tanh(omega / p.w_reg()) + wet
    }

    /// Friction held against the motor at standstill, N·m: the limit ω → 0⁺ of the friction,
    /// i.e. the dry (Coulomb or static) part in full. The regularised friction is zero at
    /// exactly ω = 0 (tanh 0 = 0), but a brake that holds the rotor still measures the stall
    /// torque less this breakaway friction (the datasheet's zero-speed point).
    pub fn friction_at_rest(&self, p_inlet: f64, p_e: f64) -> f64 {
        self.friction_parts(0.0, p_inlet, p_e).0
    }

    /// The friction as dry·tanh(ω/ω_reg) + wet: the magnitude of the dry part and the odd,
    /// smooth rest, N·m. The base T_c passes through every effect's [`Term::coulomb_nm`]
    /// (`pressure_dependent_friction`), then [`Term::dry_nm`] (`breakaway_friction`); the
    /// viscous d·ω through [`Term::wet_nm`] (`vane_friction_speed_squared`).
    #[inline(always)]
    fn friction_parts(&self, omega: f64, p_inlet: f64, p_e: f64) -> (f64, f64) {
        let p = &self.params;
        let t_base = p.t_coulomb();
        if self.effects.is_empty() {
            return (t_base, p.visc() * omega);
        }
        let t_coulomb = self
            .active()
            .fold(t_base, |t, (m, own)| m.coulomb_nm(own, t, p_inlet, p_e));
        let dry = self
            .active()
            .fold(t_coulomb, |d, (m, own)| m.dry_nm(own, d, t_base, omega));
        let wet = self
            .active()
            .fold(p.visc() * omega, |w, (m, own)| m.wet_nm(own, w, omega));
        (dry, wet)
    }

    /// What the sensors record of a channel y sampled at `times`: y through every effect's
    /// [`Term::measure`] (`sensor_lag`); y itself in the base model.
    pub fn measured(&self, times: &[f64], y: Vec<f64>) -> Vec<f64> {
        self.active()
            .fold(y, |y, (m, own)| m.measure(own, times, y))
    }

    /// The pressure control valve in front of the motor (`valve_dynamics`: first order with
    /// `valve_tau`, second order with `valve_zeta` when switched on). Every catalog entry is
    /// asked, switched on or not, because the valve exists without the effect.
    pub fn supply_valve(&self) -> SupplyValve {
        Effect::ALL
            .into_iter()
            .find_map(|e| {
                let own = self.params.effect_values(e);
                e.model().supply_valve(own, self.effects.contains(e))
            })
            .expect("the catalog describes the supply valve (valve_dynamics)")
    }

    /// Torque of the ideal motor with the forward/reverse blend of docs/model.md, "Cycle
    /// work and torque", N·m.
    fn ideal_torque(&self, p1: f64, p2: f64, pe: f64, omega: f64) -> f64 {
        self.blended_torque(p1, p2, pe, omega, |p_inlet| {
            self.filling_pressure(p_inlet, pe, omega)
        })
    }

    /// [`Motor::ideal_torque`] with the filling pressure of each inlet pressure given by
    /// `fill`: the effects' [`Motor::filling_pressure`], or the inlet pressure itself in the
    /// base model (whose right-hand side then inlines it all, without the effect checks).
    #[inline]
    fn blended_torque(
        &self,
        p1: f64,
        p2: f64,
        pe: f64,
        omega: f64,
        fill: impl Fn(f64) -> f64,
    ) -> f64 {
        let w_fwd = forward_weight(omega);
        // A saturated blend (|ω| ≳ 19 ω_b, most of a run) weighs one direction by exactly 1
        // and the other by exactly 0, so the sum below is that direction's torque as it
        // stands (up to the sign of a zero): the other direction is not formed.
        if w_fwd == 1.0 {
            return self.cycle.torque_one_way(fill(p1), p2, pe);
        }
        if w_fwd == 0.0 {
            return -self.cycle.torque_one_way(fill(p2), p1, pe);
        }
        let fill_fwd = fill(p1);
        let fill_rev = fill(p2);
        let t_fwd = self.cycle.torque_one_way(fill_fwd, p2, pe);
        let t_rev = -self.cycle.torque_one_way(fill_rev, p1, pe);
        w_fwd * t_fwd + (1.0 - w_fwd) * t_rev
    }

    /// The air torque on the rotor at state x, N·m: the ideal motor's torque T of the torque
    /// equation J·dω/dt = T − T_f − T_load, with the forward/reverse blend (docs/model.md,
    /// "Cycle work and torque"). The load that load-dependent friction
    /// ([`PressureFactor::AirTorque`]) is proportional to.
    pub fn air_torque_nm(&self, x: &State) -> f64 {
        let [p1, p2, pe, omega] = *x;
        self.ideal_torque(p1, p2, pe, omega)
    }

    /// Evaluates every flow and torque at state `x` under boundary `bc`.
    #[inline]
    pub fn balance(&self, x: &State, bc: &Boundary) -> Balance {
        let p = &self.params;
        let [p1, p2, pe, omega] = *x;
        let (flow_port1_kg_s, flow_port2_kg_s) = self.port_flows(x, bc);
        let flow_exhaust_kg_s = self.nozzle(p.c_ext()).flow(pe, bc.p_atm_pa);
        let leak = self.leak_factor(omega);
        let leak_1e_kg_s = self.nozzle(p.c_1e() * leak).flow(p1, pe);
        let leak_2e_kg_s = self.nozzle(p.c_2e() * leak).flow(p2, pe);
        let leak_12_kg_s = self.nozzle(p.c_12() * leak).flow(p1, p2);
        let (p_in, p_dis) = if omega >= 0.0 { (p1, p2) } else { (p2, p1) };
        let mut extra = [0.0; 4];
        if !self.effects.is_empty() {
            for (m, own) in self.active() {
                m.add_to_balances(own, p.values(), x, bc.p_atm_pa, &mut extra);
            }
        }
        // Computed once: the torque equation's T and the load of load-dependent friction.
        let torque_ideal_nm = self.ideal_torque(p1, p2, pe, omega);
        for t in &self.extra {
            t.add_to(x, bc.p_atm_pa, p.w_reg(), torque_ideal_nm, &mut extra);
        }
        let displacement = displacement_flows(
            &self.cycle,
            omega,
            self.filling_pressure(p_in, pe, omega),
            pe,
            self.carryover(p_dis, omega),
        );
        Balance {
            flow_port1_kg_s,
            flow_port2_kg_s,
            flow_exhaust_kg_s,
            leak_1e_kg_s,
            leak_2e_kg_s,
            leak_12_kg_s,
            displacement,
            dm1_kg_s: flow_port1_kg_s - leak_1e_kg_s - leak_12_kg_s
                + displacement.into_1_kg_s
                + extra[slot::MASS1],
            dm2_kg_s: leak_12_kg_s - flow_port2_kg_s - leak_2e_kg_s
                + displacement.into_2_kg_s
                + extra[slot::MASS2],
            dme_kg_s: leak_1e_kg_s + leak_2e_kg_s - flow_exhaust_kg_s
                + displacement.into_e_kg_s
                + extra[slot::MASSE],
            torque_ideal_nm,
            torque_friction_nm: self.friction_torque(omega, p_in, pe) + extra[slot::TORQUE],
            torque_load_nm: bc.load.torque(omega),
        }
    }

    /// Where the right-hand side has kinks (the solver's [`crate::numerics::ode::Kinks`]):
    /// for each nozzle between two states or a state and a fixed pressure (port 1 and
    /// port 2 without a throttle, exhaust, the three leakage paths), its pressure ratio less
    /// [`R_LAMINAR`], which changes sign where the nozzle enters its laminar range. A port
    /// with a throttle in series reports a constant 1 (its kink lies at the unknown pressure
    /// between the two nozzles).
    pub fn laminar_margins(&self, x: &State, bc: &Boundary) -> [f64; N_KINKS] {
        let [p1, p2, pe, _] = *x;
        let margin = |a: f64, b: f64| {
            let (lo, hi) = if a < b { (a, b) } else { (b, a) };
            if hi > 0.0 {
                lo / hi - R_LAMINAR
            } else {
                1.0
            }
        };
        let port = |c: Option<f64>, a: f64, b: f64| if c.is_some() { 1.0 } else { margin(a, b) };
        [
            port(bc.c_port1_m3_s_pa, bc.p_port1_pa, p1),
            port(bc.c_port2_m3_s_pa, p2, bc.p_port2_pa),
            margin(pe, bc.p_atm_pa),
            margin(p1, pe),
            margin(p2, pe),
            margin(p1, p2),
        ]
    }

    /// The two measured flows alone, kg/s: into port 1 and out of port 2, as in
    /// [`Balance`]. Recorded rows need only these, and a ramp has a thousand rows.
    /// (Inlined: the base right-hand side called it on every evaluation, 0.35 % of the
    /// instructions.)
    #[inline]
    pub fn port_flows(&self, x: &State, bc: &Boundary) -> (f64, f64) {
        let n = &self.nozzles;
        (
            self.flow_through(
                &n.in1,
                bc.c_port1_m3_s_pa,
                ThrottleSide::AtA,
                bc.p_port1_pa,
                x[idx::P1],
            ),
            self.flow_through(
                &n.out2,
                bc.c_port2_m3_s_pa,
                ThrottleSide::AtB,
                x[idx::P2],
                bc.p_port2_pa,
            ),
        )
    }

    /// Flow through a port's duct (conductance `c_duct`, m³/(s·Pa)) with an optional
    /// throttle (`c_throttle`) in series, from `p_a` to `p_b` (Pa absolute), kg/s; negative
    /// when the air flows from `p_b` to `p_a`. The two are ISO 6358 nozzles with the motor's
    /// critical ratio and no volume between them (`nozzle::series_flow`); `side` says at which end
    /// of the line the throttle sits, which the flow's direction does not change (reversed,
    /// the downstream element becomes the upstream one). The motor's ports call it as
    /// port 1: (`c_in1`, `Boundary::c_port1_m3_s_pa`, [`ThrottleSide::AtA`], p_port1, p_1)
    /// and port 2: (`c_out2`, `Boundary::c_port2_m3_s_pa`, [`ThrottleSide::AtB`], p_2,
    /// p_port2) (docs/model.md, "Reference experiments").
    pub fn port_flow(
        &self,
        c_duct: f64,
        c_throttle: Option<f64>,
        side: ThrottleSide,
        p_a: f64,
        p_b: f64,
    ) -> f64 {
        let duct = PreparedNozzle::new(&self.nozzle(c_duct));
        self.flow_through(&duct, c_throttle, side, p_a, p_b)
    }

    /// [`Motor::port_flow`] through a prepared duct (the motor's own ports: prepared once
    /// by [`Motor::new`]).
    #[inline(always)]
    fn flow_through(
        &self,
        duct: &PreparedNozzle,
        c_throttle: Option<f64>,
        side: ThrottleSide,
        p_a: f64,
        p_b: f64,
    ) -> f64 {
        match (c_throttle, side) {
            (None, _) => duct.flow(p_a, p_b),
            (Some(c), ThrottleSide::AtA) => series_flow(&self.nozzle(c), duct.nozzle(), p_a, p_b).0,
            (Some(c), ThrottleSide::AtB) => series_flow(duct.nozzle(), &self.nozzle(c), p_a, p_b).0,
        }
    }

    /// Time derivatives of the state, dx/dt (paper eqs. 14–15; docs/model.md, "Mechanics
    /// and friction").
    pub fn derivatives(&self, x: &State, bc: &Boundary) -> State {
        if self.effects.is_empty() && self.extra.is_empty() {
            return self.base_derivatives(x, bc);
        }
        let b = self.balance(x, bc);
        self.derivatives_from(&b)
    }

    /// dx/dt of the base model (no catalog effects, no discovered terms) without building a
    /// [`Balance`]: the flows and torques of [`Motor::balance`] in the same order of
    /// operations, less the additions of zero (the effects' terms, a leakage factor of 1, no
    /// carry-over), so the same values as [`Motor::derivatives_from`] (zero up to its
    /// sign). The right-hand side of every step of a transient: the balance's bookkeeping
    /// (thirteen fields, the effect checks) was a fifth of its instructions.
    #[inline]
    fn base_derivatives(&self, x: &State, bc: &Boundary) -> State {
        let p = &self.params;
        let [p1, p2, pe, omega] = *x;
        let (port1, port2) = self.port_flows(x, bc);
        let n = &self.nozzles;
        let exhaust = n.ext.flow(pe, bc.p_atm_pa);
        let leak_1e = n.leak_1e.flow(p1, pe);
        let leak_2e = n.leak_2e.flow(p2, pe);
        let leak_12 = n.leak_12.flow(p1, p2);
        let p_in = if omega >= 0.0 { p1 } else { p2 };
        let torque_ideal = self.blended_torque(p1, p2, pe, omega, |p_inlet| p_inlet);
        let d = displacement_flows(&self.cycle, omega, p_in, pe, 0.0);
        let dm1 = port1 - leak_1e - leak_12 + d.into_1_kg_s;
        let dm2 = leak_12 - port2 - leak_2e + d.into_2_kg_s;
        let dme = leak_1e + leak_2e - exhaust + d.into_e_kg_s;
        let friction = self.friction_torque(omega, p_in, pe);
        let [s1, s2, se] = self.rt_over_vol;
        [
            s1 * dm1,
            s2 * dm2,
            se * dme,
            (torque_ideal - friction - bc.load.torque(omega)) / p.inertia(),
        ]
    }

    /// dx/dt from an already evaluated balance.
    pub fn derivatives_from(&self, b: &Balance) -> State {
        let p = &self.params;
        let [s1, s2, se] = self.rt_over_vol;
        [
            s1 * b.dm1_kg_s,
            s2 * b.dm2_kg_s,
            se * b.dme_kg_s,
            (b.torque_ideal_nm - b.torque_friction_nm - b.torque_load_nm) / p.inertia(),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn volumes_store_exactly_what_the_ports_exchange() {
        let m = Motor::default_motor();
        let bc = Boundary::supplied(7.3e5, 1.01325e5, Load::None);
        for x in [
            [6e5, 1.5e5, 1.3e5, 800.0],
            [3e5, 4e5, 2e5, -300.0],
            [2e5, 1e5, 1e5, 0.0],
        ] {
            let b = m.balance(&x, &bc);
            let stored = b.dm1_kg_s + b.dm2_kg_s + b.dme_kg_s;
            let exchanged = b.flow_port1_kg_s - b.flow_port2_kg_s - b.flow_exhaust_kg_s;
            assert_eq!(
                m.port_flows(&x, &bc),
                (b.flow_port1_kg_s, b.flow_port2_kg_s)
            );
            assert!(
                (stored - exchanged).abs() < 1e-15,
                "{stored} vs {exchanged}"
            );
        }
    }
    /// The base model's right-hand side without a balance gives what the balance gives
    /// (equal as numbers), over states on both sides of every nozzle's thresholds, both
    /// directions of rotation and both kinds of port.
    #[test]
    fn base_derivatives_equal_the_balance_path() {
        let m = Motor::default_motor();
        let mut checked = 0;
        for (c1, c2) in [(None, None), (Some(2e-9), None), (None, Some(3e-9))] {
            let bc = Boundary {
                c_port1_m3_s_pa: c1,
                c_port2_m3_s_pa: c2,
                ..Boundary::supplied(6.3e5, 101_325.0, Load::ViscousBrake { c_nm_s_rad: 2e-4 })
            };
            for p1 in [0.9e5, 101_330.0, 2e5, 6.3e5, 7e5] {
                for p2 in [101_300.0, 1.2e5, 4e5] {
                    for pe in [101_325.0, 101_400.0, 1.5e5] {
                        for w in [-700.0, -0.01, 0.0, 0.3, 900.0] {
                            let x = [p1, p2, pe, w];
                            let want = m.derivatives_from(&m.balance(&x, &bc));
                            assert_eq!(m.base_derivatives(&x, &bc), want, "{x:?} {c1:?} {c2:?}");
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert_eq!(checked, 3 * 5 * 3 * 3 * 5);
    }

    /// Load-dependent friction k·|T_air|·tanh(ω/ω_reg) (k > 0) adds exactly that to the
    /// friction torque, with T_air the torque equation's own air torque, and takes power out
    /// at every state (T_loss·ω ≥ 0): driving forwards and backwards, and braked (the air
    /// torque against the rotation, where |T_air| still loads the bearings).
    #[test]
    fn load_dependent_friction_is_a_loss_never_a_gain() {
        let k = 0.07;
        let term = ExtraTerm {
            balance: BalanceId::Torque,
            pressure: PressureFactor::AirTorque,
            speed: SpeedFactor::Sign,
            coefficient: k,
        };
        let plain = Motor::default_motor();
        let loaded = Motor::default_motor().with_extra(&[term]);
        let bc = Boundary::supplied(7.3e5, 1.01325e5, Load::None);
        let w_reg = plain.params.w_reg();
        let mut braked = 0;
        for p1 in [1.0e5, 2.5e5, 5e5, 7e5] {
            for p2 in [1.0e5, 2e5, 4e5, 7e5] {
                for w in [-900.0, -30.0, -0.1, 0.0, 0.05, 40.0, 800.0] {
                    let x = [p1, p2, 1.2e5, w];
                    let t_air = plain.air_torque_nm(&x);
                    assert_eq!(t_air, plain.balance(&x, &bc).torque_ideal_nm);
                    let loss = loaded.balance(&x, &bc).torque_friction_nm
                        - plain.balance(&x, &bc).torque_friction_nm;
                    let want = k * t_air.abs() * (w / w_reg).tanh();
                    assert!((loss - want).abs() <= 1e-15 * t_air.abs().max(1.0), "{x:?}");
                    assert!(loss * w >= 0.0, "a gain of {} W at {x:?}", -loss * w);
                    braked += usize::from(t_air * w < 0.0 && loss * w > 0.0);
                }
            }
        }
        assert!(braked > 0, "no braked state was tried");
    }

    /// A throttle in front of port 1 passes supply → throttle → in_1 → V_1. With a choked
    /// throttle smaller than the duct the flow is the throttle's own, C_th·ρ0·p_s; in the
    /// other order (duct first) the throttle sees only the pressure p_m behind the duct,
    /// which for b = 0.5 solves √(1 − (2·p_m/p_s − 1)²) = k·p_m/p_s, k = C_th/C_duct, i.e.
    /// p_m/p_s = 1/(1 + k²/4): the order changes the flow by that factor.
    #[test]
    fn an_inlet_throttle_sits_in_front_of_the_duct() {
        use crate::units::constants::RHO0_KG_M3;
        let m = Motor::default_motor();
        assert_eq!(m.params.b_crit(), 0.5);
        let (c_duct, c_thr) = (m.params.c_in1(), 2e-9);
        let (p_s, p_1) = (7e5, 1e5);
        let bc = Boundary {
            c_port1_m3_s_pa: Some(c_thr),
            ..Boundary::supplied(p_s, 101_325.0, Load::None)
        };
        let (flow, _) = m.port_flows(&[p_1, 1.1e5, 1.1e5, 0.0], &bc);
        let throttle_first = c_thr * RHO0_KG_M3 * p_s;
        assert!(
            (flow / throttle_first - 1.0).abs() < 1e-12,
            "{flow} vs {throttle_first}"
        );
        let k = c_thr / c_duct;
        let duct_first = throttle_first / (1.0 + k * k / 4.0);
        let other = m.port_flow(c_duct, Some(c_thr), ThrottleSide::AtB, p_s, p_1);
        assert!(
            (other / duct_first - 1.0).abs() < 1e-9,
            "{other} vs {duct_first}"
        );
        assert!(
            flow / other - 1.0 > 0.01,
            "the order must matter: {flow} vs {other}"
        );
        // Reversed (port 1 as exhaust), the throttle stays on the line's outer end.
        let back = m.port_flow(c_duct, Some(c_thr), ThrottleSide::AtA, p_1, p_s);
        assert_eq!(
            back,
            -m.port_flow(c_duct, Some(c_thr), ThrottleSide::AtB, p_s, p_1)
        );
    }

    /// A symmetric motor run backwards (supply at port 2, port 1 to atmosphere) with the
    /// throttle moved to port 2 is the forward run mirrored: ports swapped, ω negated.
    #[test]
    fn a_reversed_motor_with_the_throttle_moved_is_the_mirror_image() {
        let m = Motor::default_motor();
        let p = &m.params;
        assert_eq!(
            (p.c_in1(), p.vol1(), p.c_1e()),
            (p.c_out2(), p.vol2(), p.c_2e())
        );
        let load = Load::ViscousBrake { c_nm_s_rad: 1e-4 };
        for c in [1e-9, 2.8e-9, 1e-8] {
            let fwd = Boundary {
                c_port1_m3_s_pa: Some(c),
                ..Boundary::supplied(7.3e5, 101_325.0, load)
            };
            let rev = Boundary {
                p_port1_pa: 101_325.0,
                p_port2_pa: 7.3e5,
                c_port1_m3_s_pa: None,
                c_port2_m3_s_pa: Some(c),
                ..fwd
            };
            for [p1, p2, pe, w] in [
                [4e5, 1.6e5, 1.2e5, 500.0],
                [6.9e5, 1.05e5, 1.02e5, 20.0],
                [7.5e5, 2e5, 1.3e5, 900.0],
            ] {
                let f = m.derivatives(&[p1, p2, pe, w], &fwd);
                let g = m.derivatives(&[p2, p1, pe, -w], &rev);
                let mirrored = [g[1], g[0], g[2], -g[3]];
                for i in 0..N_STATES {
                    let scale = f[i].abs().max(1.0);
                    assert!(
                        (f[i] - mirrored[i]).abs() <= 1e-12 * scale,
                        "C = {c:e}, row {i}: {} vs {}",
                        f[i],
                        mirrored[i]
                    );
                }
            }
        }
    }
}
