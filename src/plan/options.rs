//! What a plan is asked for: the user's operating points (supply pressures, optionally
//! speeds), the candidates' costs in rig time and how many to detail. SI throughout; the
//! command line converts.

use super::PlanError;

/// A kind of measurement the planner weighs (docs/plan.md, "Candidates").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum CandidateKind {
    /// The key figures of a catalogue row (stall torque, maximum power with its speed and
    /// air, free speed and its air) at one supply pressure, weighed as a page's.
    KeyFigures,
    /// The stall torque at one supply pressure (brake locked), repeated readings.
    StallTorque,
    /// The free speed and the air flow into port 1 there at one supply pressure (shaft
    /// free).
    AirFlow,
    /// A datasheet sweep: torque and air at imposed speeds from near stall to near free
    /// speed at one supply pressure.
    DatasheetSweep,
    /// A slow supply-pressure ramp with the shaft free: speed and air against pressure.
    PressureRamp,
    /// An outlet-throttle ramp at one supply pressure with the shaft free: speed and air
    /// against the throttle's conductance.
    OutletThrottleRamp,
    /// A load step at one supply pressure: the brake's torque stepped from 0 to half the
    /// stall torque; the steady speed and air at both levels.
    LoadStep,
}

impl CandidateKind {
    /// Every kind, in the order the tables list them.
    pub const ALL: [CandidateKind; 7] = [
        CandidateKind::KeyFigures,
        CandidateKind::StallTorque,
        CandidateKind::AirFlow,
        CandidateKind::DatasheetSweep,
        CandidateKind::PressureRamp,
        CandidateKind::OutletThrottleRamp,
        CandidateKind::LoadStep,
    ];

    /// The name the command line's `--costs` and the outputs use.
    pub fn name(self) -> &'static str {
        match self {
            CandidateKind::KeyFigures => "key_figures",
            CandidateKind::StallTorque => "stall_torque",
            CandidateKind::AirFlow => "air_flow",
            CandidateKind::DatasheetSweep => "datasheet",
            CandidateKind::PressureRamp => "pressure_ramp",
            CandidateKind::OutletThrottleRamp => "outlet_throttle",
            CandidateKind::LoadStep => "load_step",
        }
    }

    /// The kind of a name of [`CandidateKind::name`].
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|k| k.name() == name)
    }

    /// Default rig time, hours: setting up and running the measurement on a rig that is
    /// already mounted (a first guess; every user's rig differs, so `--costs` overrides it).
    pub fn default_cost_h(self) -> f64 {
        match self {
            CandidateKind::KeyFigures => 0.5,
            CandidateKind::StallTorque | CandidateKind::AirFlow => 0.25,
            CandidateKind::DatasheetSweep => 2.0,
            CandidateKind::PressureRamp => 1.0,
            CandidateKind::OutletThrottleRamp => 1.5,
            CandidateKind::LoadStep => 0.5,
        }
    }
}

/// How many candidates are detailed (bands before and after, rig settings) by default.
pub const DEFAULT_TOP: usize = 3;

/// What to plan for.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanOptions {
    /// The user's supply pressures, Pa absolute: where the bands should shrink, and where
    /// the candidates at one pressure are measured.
    pub pressures_pa: Vec<f64>,
    /// The user's shaft speeds, rad/s (the output shaft's for a geared motor): the bands
    /// of torque, power and air there at each pressure. `None`: the catalogue figures at
    /// each pressure (maximum power, free speed, stall torque, air at maximum power).
    pub speeds_rad_s: Option<Vec<f64>>,
    /// Atmosphere, Pa absolute.
    pub p_atm_pa: f64,
    /// Rig time of a kind, hours, where it differs from [`CandidateKind::default_cost_h`].
    pub costs_h: Vec<(CandidateKind, f64)>,
    /// As `PredictOptions::fixed_spread`: the factor (95 %) within which parameters the fit
    /// held fixed or could not identify are taken as uncertain (`None`: exact).
    pub fixed_spread: Option<f64>,
    /// Candidates detailed in the outputs.
    pub top: usize,
    /// The kinds weighed (`None`: every kind).
    pub kinds: Option<Vec<CandidateKind>>,
}

impl PlanOptions {
    /// The plan at `pressures_pa` (Pa absolute) and atmosphere `p_atm_pa`, catalogue
    /// figures, default costs, no spread, the top three detailed.
    pub fn new(pressures_pa: Vec<f64>, p_atm_pa: f64) -> Self {
        Self {
            pressures_pa,
            speeds_rad_s: None,
            p_atm_pa,
            costs_h: Vec::new(),
            fixed_spread: None,
            top: DEFAULT_TOP,
            kinds: None,
        }
    }

    /// Refuses what cannot be planned: no pressure, a pressure, speed or cost that is not a
    /// positive number, a spread that is not a factor above 1, no candidate to detail.
    pub fn check(&self) -> Result<(), PlanError> {
        let positive = |v: f64| v.is_finite() && v > 0.0;
        if self.pressures_pa.is_empty() {
            return Err(PlanError::NoPressures);
        }
        let all = self.pressures_pa.iter().chain([&self.p_atm_pa]);
        if let Some(p) = all.copied().find(|p| !positive(*p)) {
            return Err(PlanError::BadPressure(p));
        }
        if let Some(p) = self.pressures_pa.iter().find(|p| **p <= self.p_atm_pa) {
            return Err(PlanError::BadPressure(*p));
        }
        let speeds = self.speeds_rad_s.iter().flatten();
        if let Some(w) = speeds.copied().find(|w| !(w.is_finite() && *w >= 0.0)) {
            return Err(PlanError::BadSpeed(w));
        }
        if self.speeds_rad_s.as_ref().is_some_and(|s| s.is_empty()) {
            return Err(PlanError::BadSpeed(f64::NAN));
        }
        if let Some((k, h)) = self.costs_h.iter().find(|(_, h)| !positive(*h)) {
            return Err(PlanError::BadCost {
                kind: k.name(),
                hours: *h,
            });
        }
        if let Some(f) = self.fixed_spread.filter(|f| !(f.is_finite() && *f > 1.0)) {
            return Err(PlanError::BadSpread(f));
        }
        if self.top == 0 {
            return Err(PlanError::BadTop);
        }
        if self.kinds.as_ref().is_some_and(|k| k.is_empty()) {
            return Err(PlanError::NoKinds);
        }
        Ok(())
    }

    /// Whether candidates of `kind` are weighed.
    pub fn weighs(&self, kind: CandidateKind) -> bool {
        self.kinds.as_ref().is_none_or(|k| k.contains(&kind))
    }

    /// The rig time of `kind`, hours: the user's, else the default.
    pub fn cost_h(&self, kind: CandidateKind) -> f64 {
        self.costs_h
            .iter()
            .rev()
            .find(|(k, _)| *k == kind)
            .map_or(kind.default_cost_h(), |(_, h)| *h)
    }
}
