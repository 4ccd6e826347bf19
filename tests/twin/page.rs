//! Catalogue pages of random motors, printed the way makers print them, with the twin's own
//! truth beside them.
//!
//! A motor ([`random_motor`]) is drawn around size-scaled values with a spread of its own
//! per parameter (a random effect per motor), not around vanefit's defaults: the
//! displacement log-uniform in 1.5–15 cm³, each other parameter a log-normal factor on its
//! value at the AR034-11 motor of the paper scaled by geometric similarity (s = V_disp/3.8 cm³:
//! areas, hence conductances, × s^⅔; volumes and dry friction × s; viscous friction × s^{4/3};
//! inertia × s^{5/3}). [`SPREAD`] lists the spreads and why.
//!
//! A page ([`print_page`]) is one supply pressure (6.3 bar g, 6 or 7 bar g, 5 bar g, 90 psi g),
//! sparse curve points at round speeds and key figures to 3 significant digits in units drawn
//! per page (rpm, r/min, N·m, lbf·in, W, kW, hp, cfm, scfm, l/s, l/min, l/min ANR, l/s ANR,
//! Nl/min, m³/min), the displacement rounded to 2 digits (missing from a share of pages), no
//! vanes, dead volume or expansion ratio. What is printed, in what unit, varies with the seed
//! ([`PageStyle`]); the format is docs/formats.md, "Catalogue data".

use super::catalogue::{catalogue_row, curve_point, TwinRow};
use super::experiment::Conditions;
use super::motor::{TwinMotor, P_ATM_PA};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::fmt::Write as _;
use std::path::Path;

/// Displacement of the reference motor AR034-11, m³ (the paper's motor).
pub const V_REF_M3: f64 = 3.8e-6;

/// 1σ of ln(factor) of each parameter's random effect around its size-scaled value, and the
/// ranges of the parameters drawn uniformly. Where each comes from:
/// - conductances (ports and leaks, each on its own): 0.35 — vane motors of one size from
///   different makers differ in port size and vane fit by about ×/÷ 1.4 (leaks are a gap
///   and wear away, the ports are drilled to the maker's choice);
/// - dead volume: 0.4, and the lumped volumes: 0.4 — pocket and channel volumes are design
///   choices that similarity does not fix;
/// - Coulomb friction: 0.5, viscous friction: 0.5 — friction is the least reproducible motor
///   property (vane spring, lubrication, seal type);
/// - inertia: 0.3 (does not act on a steady-state page);
/// - expansion ratio: ε − 1 = 0.071 × a factor of σ 0.5 (inlet and exhaust timing differ
///   between designs);
/// - vanes z: 4 to 7; polytropic index n: 1.15 to 1.4; critical ratio b: 0.4 to 0.55 (ISO
///   6358 values of short drilled ports).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spread {
    /// σ of ln of each conductance factor.
    pub conductance: f64,
    /// σ of ln of the dead-volume factor.
    pub dead_volume: f64,
    /// σ of ln of each lumped-volume factor.
    pub volumes: f64,
    /// σ of ln of the Coulomb- and viscous-friction factors.
    pub friction: f64,
    /// σ of ln of the inertia factor.
    pub inertia: f64,
    /// σ of ln of the factor on ε − 1.
    pub expansion: f64,
    /// Range of the polytropic index.
    pub n_poly: (f64, f64),
    /// Range of the critical pressure ratio.
    pub b_crit: (f64, f64),
}

/// The spreads of the random motors (see [`Spread`] for where they come from).
pub const SPREAD: Spread = Spread {
    conductance: 0.35,
    dead_volume: 0.4,
    volumes: 0.4,
    friction: 0.5,
    inertia: 0.3,
    expansion: 0.5,
    n_poly: (1.15, 1.4),
    b_crit: (0.4, 0.55),
};

fn normal(rng: &mut Xoshiro256PlusPlus) -> f64 {
    rng.sample::<f64, _>(rand_distr::StandardNormal)
}

/// A random motor of 1.5 to 15 cm³ drawn from `seed` with the spreads `sp` (see the module
/// documentation). The size-scaled centres are the paper's AR034-11 values (ports
/// 6.758e-9 and 1.171e-8 m³/(s·Pa), leaks 2.078e-9 and 7.62e-10, dead volume 0.1 cm³, volumes
/// 2 cm³, inertia 2e-4 kg·m², friction 0.02 N·m and 6e-5 N·m·s/rad) at 3.8 cm³.
pub fn random_motor(seed: u64, sp: &Spread) -> TwinMotor {
    let mut rng = motor_rng(seed);
    let v_disp = (1.5e-6f64.ln() + rng.random::<f64>() * 10f64.ln()).exp();
    draw_around(&mut rng, v_disp, sp)
}

/// [`random_motor`]'s motor `seed` with the displacement `v_disp_m3` instead of its own:
/// the same size laws (geometric similarity from AR034-11, see the module documentation),
/// the same spreads and the same random effects (the seed's size draw is made and set
/// aside, so that `random_motor_sized(seed, v, sp)` is `random_motor(seed, sp)` at its own
/// size). For motors of any size (tests/twin/sizes.rs draws them per size band).
pub fn random_motor_sized(seed: u64, v_disp_m3: f64, sp: &Spread) -> TwinMotor {
    let mut rng = motor_rng(seed);
    let _size_draw = rng.random::<f64>();
    draw_around(&mut rng, v_disp_m3, sp)
}

fn motor_rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x9a6e_5000_0000_0001)
}

/// A motor of displacement `v_disp` (m³) around AR034-11's values scaled to its size, each
/// parameter × its own log-normal factor of [`Spread`].
fn draw_around(rng: &mut Xoshiro256PlusPlus, v_disp: f64, sp: &Spread) -> TwinMotor {
    let s = v_disp / V_REF_M3;
    let mut ln = |sigma: f64| (sigma * normal(rng)).exp();
    let area = s.powf(2.0 / 3.0);
    let m = TwinMotor {
        c_in1: 6.758e-9 * area * ln(sp.conductance),
        c_out2: 6.758e-9 * area * ln(sp.conductance),
        c_ext: 1.171e-8 * area * ln(sp.conductance),
        c_1e: 2.078e-9 * area * ln(sp.conductance),
        c_2e: 2.078e-9 * area * ln(sp.conductance),
        c_12: 7.62e-10 * area * ln(sp.conductance),
        v_dead: 0.1e-6 * s * ln(sp.dead_volume),
        vol1: 2e-6 * s * ln(sp.volumes),
        vol2: 2e-6 * s * ln(sp.volumes),
        vole: 2e-6 * s * ln(sp.volumes),
        inertia: 2e-4 * s.powf(5.0 / 3.0) * ln(sp.inertia),
        t_coulomb: 0.02 * s * ln(sp.friction),
        visc: 6e-5 * s.powf(4.0 / 3.0) * ln(sp.friction),
        eps: 1.0 + 0.071 * ln(sp.expansion),
        v_disp,
        ..TwinMotor::default()
    };
    TwinMotor {
        z: rng.random_range(4..=7) as f64,
        n_poly: rng.random_range(sp.n_poly.0..=sp.n_poly.1),
        b_crit: rng.random_range(sp.b_crit.0..=sp.b_crit.1),
        ..m
    }
}

/// A unit as a page prints it: the text after the number in a key figure, the CSV column
/// suffix, and the factor from SI (value in the unit = SI × factor).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PageUnit {
    /// As printed in a key figure, e.g. `lbf·in`.
    pub printed: &'static str,
    /// The CSV column suffix, e.g. `lbf_in`.
    pub column: &'static str,
    /// Value in this unit per SI unit.
    pub per_si: f64,
}

const RPM: f64 = 30.0 / std::f64::consts::PI;
/// N·m per lbf·in: 4.4482216152605 N × 0.0254 m.
const NM_PER_LBF_IN: f64 = 4.448_221_615_260_5 * 0.0254;
/// W per mechanical horsepower (550 ft·lbf/s).
const W_PER_HP: f64 = 550.0 * 4.448_221_615_260_5 * 0.3048;
/// Densities of the air references, kg/m³: ANR (ISO 8778), free air (ISO 1217: 100 kPa,
/// 20 °C, dry), US standard air (0.075 lb/ft³), normal (DIN 1343: 101.325 kPa, 0 °C).
const RHO_ANR: f64 = 1.185;
const RHO_FREE: f64 = 100_000.0 / (287.052_87 * 293.15);
const RHO_SCFM: f64 = 0.075 * 0.453_592_37 / 0.028_316_846_592;
const RHO_NORMAL: f64 = 101_325.0 / (287.052_87 * 273.15);
const FT3_M3: f64 = 0.028_316_846_592;

/// Speed units (from rad/s).
pub const SPEED_UNITS: [PageUnit; 2] = [
    PageUnit {
        printed: "rpm",
        column: "rpm",
        per_si: RPM,
    },
    PageUnit {
        printed: "r/min",
        column: "r_min",
        per_si: RPM,
    },
];
/// Torque units (from N·m).
pub const TORQUE_UNITS: [PageUnit; 3] = [
    PageUnit {
        printed: "N·m",
        column: "nm",
        per_si: 1.0,
    },
    PageUnit {
        printed: "Nm",
        column: "nm",
        per_si: 1.0,
    },
    PageUnit {
        printed: "lbf·in",
        column: "lbf_in",
        per_si: 1.0 / NM_PER_LBF_IN,
    },
];
/// Power units (from W).
pub const POWER_UNITS: [PageUnit; 3] = [
    PageUnit {
        printed: "W",
        column: "w",
        per_si: 1.0,
    },
    PageUnit {
        printed: "kW",
        column: "kw",
        per_si: 1e-3,
    },
    PageUnit {
        printed: "hp",
        column: "hp",
        per_si: 1.0 / W_PER_HP,
    },
];
/// Air-consumption units (from kg/s).
pub const AIR_UNITS: [PageUnit; 8] = [
    PageUnit {
        printed: "l/min ANR",
        column: "l_min_anr",
        per_si: 60e3 / RHO_ANR,
    },
    PageUnit {
        printed: "l/s ANR",
        column: "l_s_anr",
        per_si: 1e3 / RHO_ANR,
    },
    PageUnit {
        printed: "l/s",
        column: "l_s",
        per_si: 1e3 / RHO_FREE,
    },
    PageUnit {
        printed: "l/min",
        column: "l_min",
        per_si: 60e3 / RHO_FREE,
    },
    PageUnit {
        printed: "m3/min",
        column: "m3_min",
        per_si: 60.0 / RHO_FREE,
    },
    PageUnit {
        printed: "cfm",
        column: "cfm",
        per_si: 60.0 / RHO_FREE / FT3_M3,
    },
    PageUnit {
        printed: "scfm",
        column: "scfm",
        per_si: 60.0 / RHO_SCFM / FT3_M3,
    },
    PageUnit {
        printed: "Nl/min",
        column: "nl_min",
        per_si: 60e3 / RHO_NORMAL,
    },
];
/// Supply pressures as printed, with their gauge value in bar.
pub const SUPPLIES: [(&str, f64); 6] = [
    ("6.3 bar(g)", 6.3),
    ("6.3 bar_g", 6.3),
    ("6 bar(g)", 6.0),
    ("7 bar(g)", 7.0),
    ("5 bar(g)", 5.0),
    ("90 psi(g)", 90.0 * 0.068_947_572_931_683_6),
];

/// Key figures in the order of [`TwinRow`] and vanefit's `catalogue.csv`.
pub const FIGURES: [&str; 7] = [
    "free_speed",
    "max_power",
    "speed_at_max_power",
    "torque_at_max_power",
    "stall_torque",
    "air_at_max_power",
    "air_at_free_speed",
];

/// The figures of a row in [`FIGURES`] order, SI.
pub fn row_values(r: &TwinRow) -> [f64; 7] {
    [
        r.free_speed_rad_s,
        r.max_power_w,
        r.speed_at_max_power_rad_s,
        r.torque_at_max_power_nm,
        r.stall_torque_nm,
        r.air_at_max_power_kg_s,
        r.air_at_free_speed_kg_s,
    ]
}

/// How a page is printed, drawn from a seed.
#[derive(Debug, Clone, PartialEq)]
pub struct PageStyle {
    /// Supply pressure as printed and in bar g.
    pub supply: (&'static str, f64),
    /// Units of speed, torque, power, air.
    pub units: [PageUnit; 4],
    /// Which of [`FIGURES`] are printed.
    pub figures: [bool; 7],
    /// Number of curve points (0: no curves file).
    pub curve_points: usize,
    /// Chance that a curve cell is printed, per column torque, power, air.
    pub cell_share: [f64; 3],
    /// The displacement rounded to 2 digits, or `None` when the page does not print it.
    pub displacement: bool,
    /// Seed of the cell draws.
    pub seed: u64,
}

/// A page style from `seed`: displacement missing on about one page in six, no curves on one
/// in ten, 3 to 9 curve points, each figure printed with chance 0.6–0.9, at least three.
pub fn page_style(seed: u64) -> PageStyle {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x5e1e_c7ed_0000_0002);
    let pick = |rng: &mut Xoshiro256PlusPlus, n: usize| rng.random_range(0..n);
    let supply = SUPPLIES[pick(&mut rng, SUPPLIES.len())];
    let units = [
        SPEED_UNITS[pick(&mut rng, SPEED_UNITS.len())],
        TORQUE_UNITS[pick(&mut rng, TORQUE_UNITS.len())],
        POWER_UNITS[pick(&mut rng, POWER_UNITS.len())],
        AIR_UNITS[pick(&mut rng, AIR_UNITS.len())],
    ];
    let share = [0.9, 0.9, 0.6, 0.6, 0.8, 0.7, 0.6];
    let mut figures = [false; 7];
    while figures.iter().filter(|f| **f).count() < 3 {
        figures = std::array::from_fn(|k| rng.random::<f64>() < share[k]);
        // A figure at max power comes with its speed ("0.1 kW at 5000 rpm"): vanefit
        // compares it at that speed and refuses it alone.
        figures[2] |= figures[1] || figures[3] || figures[5];
        // Likewise the air at free speed with the free speed.
        figures[0] |= figures[6];
    }
    let curve_points = if rng.random::<f64>() < 0.1 {
        0
    } else {
        rng.random_range(3..=9)
    };
    let cell_share = [
        rng.random_range(0.5..=1.0),
        rng.random_range(0.3..=1.0),
        rng.random_range(0.3..=1.0),
    ];
    PageStyle {
        supply,
        units,
        figures,
        curve_points,
        cell_share,
        displacement: rng.random::<f64>() >= 1.0 / 6.0,
        seed: rng.random(),
    }
}

/// `x` rounded to `digits` significant digits and printed as makers do (no exponent:
/// 12200, 0.0979).
pub fn significant(x: f64, digits: usize) -> String {
    if x == 0.0 {
        return "0".into();
    }
    let rounded: f64 = format!("{:.*e}", digits - 1, x).parse().unwrap();
    let mag = rounded.abs().log10().floor() as i32;
    let decimals = (digits as i32 - 1 - mag).max(0) as usize;
    format!("{rounded:.decimals$}")
}

/// A page as written, with what the twin knows about it.
#[derive(Debug, Clone, PartialEq)]
pub struct Page {
    /// The motor.
    pub motor: TwinMotor,
    /// How it was printed.
    pub style: PageStyle,
    /// The twin's row at the page's supply pressure.
    pub row: TwinRow,
}

/// Round speed step of a curve: 1, 2 or 5 × 10ⁿ rpm giving at most `n` points below the free
/// speed.
pub fn speed_step_rpm(free_rpm: f64, n: usize) -> f64 {
    let raw = free_rpm / (n as f64 + 0.5);
    let decade = 10f64.powf(raw.log10().floor());
    [1.0, 2.0, 2.5, 5.0, 10.0]
        .iter()
        .map(|k| k * decade)
        .find(|s| *s >= raw)
        .unwrap_or(10.0 * decade)
}

/// Writes the page of `motor` in `style` into `dir` (rig.toml and, with curves,
/// curves.csv); returns the page or the twin's failure.
pub fn print_page(dir: &Path, motor: &TwinMotor, style: &PageStyle) -> Result<Page, String> {
    let c = Conditions {
        p_supply_pa: P_ATM_PA + style.supply.1 * 1e5,
        ..Conditions::default()
    };
    let row = catalogue_row(motor, &c)?;
    let [speed, torque, power, air] = style.units;
    let fig_units = [speed, power, speed, torque, torque, air, air];
    let mut toml = String::new();
    writeln!(
        toml,
        "description = \"a maker's page (tests/twin/page.rs)\"\n"
    )
    .unwrap();
    writeln!(toml, "[motor]\nname = \"twin page motor\"").unwrap();
    if style.displacement {
        // "3.8 cm³" as the page prints it, in the SI key the format asks for.
        writeln!(
            toml,
            "displacement_m3 = {}e-6",
            significant(motor.v_disp * 1e6, 2)
        )
        .unwrap();
    }
    writeln!(toml, "\n[[experiment]]\nkind = \"catalogue\"").unwrap();
    if style.curve_points > 0 {
        writeln!(toml, "file = \"curves.csv\"").unwrap();
    }
    writeln!(
        toml,
        "p_supply = \"{}\"\n\n[experiment.figures]",
        style.supply.0
    )
    .unwrap();
    for (k, v) in row_values(&row).iter().enumerate() {
        if style.figures[k] {
            let u = fig_units[k];
            writeln!(
                toml,
                "{} = \"{} {}\"",
                FIGURES[k],
                significant(v * u.per_si, 3),
                u.printed
            )
            .unwrap();
        }
    }
    std::fs::write(dir.join("rig.toml"), toml).map_err(|e| e.to_string())?;
    if style.curve_points > 0 {
        let csv = curves_csv(motor, &c, style, &row)?;
        std::fs::write(dir.join("curves.csv"), csv).map_err(|e| e.to_string())?;
    }
    Ok(Page {
        motor: motor.clone(),
        style: style.clone(),
        row,
    })
}

/// The curves file: round speeds from 0 below the free speed, each cell printed by chance
/// (at least one per row), 3 significant digits.
fn curves_csv(
    m: &TwinMotor,
    c: &Conditions,
    style: &PageStyle,
    row: &TwinRow,
) -> Result<String, String> {
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(style.seed);
    let [speed, torque, power, air] = style.units;
    let free_rpm = row.free_speed_rad_s * RPM;
    let step = speed_step_rpm(free_rpm, style.curve_points);
    let mut out = format!(
        "speed_{},torque_{},power_{},air_{}\n",
        speed.column, torque.column, power.column, air.column
    );
    let mut k = 0;
    while (k as f64) * step < 0.97 * free_rpm {
        let printed = significant(k as f64 * step, 3);
        k += 1;
        let w = printed.parse::<f64>().unwrap() / RPM;
        let (t, q) = curve_point(m, c, w)?;
        let mut cells = [0, 1, 2].map(|j| rng.random::<f64>() < style.cell_share[j]);
        if w == 0.0 {
            cells[1] = false; // no power at standstill
        }
        if !cells.iter().any(|x| *x) {
            cells[0] = true;
        }
        let cell = |on: bool, v: f64| if on { significant(v, 3) } else { String::new() };
        writeln!(
            out,
            "{},{},{},{}",
            printed,
            cell(cells[0], t * torque.per_si),
            cell(cells[1], t * w * power.per_si),
            cell(cells[2], q * air.per_si)
        )
        .unwrap();
    }
    Ok(out)
}

/// The twin's rows at `bar_g` (gauge, bar) and the four correction factors of each against
/// the row at `reference_bar_g` (docs/model.md, "Reference experiments": power = max power,
/// speed = free speed, torque = stall torque, air = air at max power).
pub fn truth(
    m: &TwinMotor,
    bar_g: &[f64],
    reference_bar_g: f64,
) -> Result<(Vec<TwinRow>, Vec<[f64; 4]>), String> {
    let at = |b: f64| {
        catalogue_row(
            m,
            &Conditions {
                p_supply_pa: P_ATM_PA + b * 1e5,
                ..Conditions::default()
            },
        )
    };
    let reference = at(reference_bar_g)?;
    let rows = bar_g
        .iter()
        .map(|b| at(*b))
        .collect::<Result<Vec<_>, _>>()?;
    let factors = rows
        .iter()
        .map(|r| {
            [
                r.max_power_w / reference.max_power_w,
                r.free_speed_rad_s / reference.free_speed_rad_s,
                r.stall_torque_nm / reference.stall_torque_nm,
                r.air_at_max_power_kg_s / reference.air_at_max_power_kg_s,
            ]
        })
        .collect();
    Ok((rows, factors))
}
