//! Catalogue pages in the styles makers print them, for motors of any size: a full page, a
//! table row, a geared motor's page (figures at the output shaft), a page without the
//! displacement, a page with key figures at a second supply pressure, and a full page in
//! makers' own spellings of the units (U/min, ft-lb, Nl/s, barg, psig, …).
//!
//! A styled page starts from [`page_style`] of its seed (supply, units, which cells of the
//! curves are printed) and sets what its kind fixes. The truth beside it
//! ([`styled_truth`]) is the twin's catalogue row at any pressure, at the shaft the page
//! prints: for a geared motor of ratio G (motor speed / output speed) and gearbox
//! efficiency η, speeds ω/G, torques η·G·T, power η·P, air unchanged.

use super::catalogue::{catalogue_row, curve_point, TwinRow};
use super::experiment::Conditions;
use super::motor::{TwinMotor, P_ATM_PA};
use super::page::{
    page_style, row_values, significant, speed_step_rpm, PageStyle, PageUnit, FIGURES,
};
use rand::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;
use std::fmt::Write as _;
use std::path::Path;

/// The kinds of page of the tables (docs/validation.md, "Every size and page style").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum PageKind {
    /// Curves and the six figures (and the air at free speed on some), with displacement.
    Full,
    /// A catalogue table's row: free speed, max power with its speed and torque, air at max
    /// power; no curves, no stall torque, no displacement, no vane count.
    TableRow,
    /// A full page of a geared motor, figures at the output shaft, `gear_ratio` under
    /// `[motor]` and on half of them `gear_efficiency`.
    Geared,
    /// A full page without the displacement.
    NoDisplacement,
    /// A full page with the key figures at a second supply pressure too.
    SecondPressure,
    /// A full page whose key figures and supply are in makers' spellings.
    MakersSpelling,
}

impl PageKind {
    /// Every kind, in the tables' order.
    pub const ALL: [PageKind; 6] = [
        PageKind::Full,
        PageKind::TableRow,
        PageKind::Geared,
        PageKind::NoDisplacement,
        PageKind::SecondPressure,
        PageKind::MakersSpelling,
    ];

    /// Its name in the tables and in environment knobs.
    pub fn name(self) -> &'static str {
        match self {
            PageKind::Full => "full",
            PageKind::TableRow => "table_row",
            PageKind::Geared => "geared",
            PageKind::NoDisplacement => "no_displacement",
            PageKind::SecondPressure => "second_pressure",
            PageKind::MakersSpelling => "makers_spelling",
        }
    }
}

/// A gearbox on the motor's shaft.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gear {
    /// Ratio G, motor speed / output speed, as printed (3 significant digits), 1.
    pub ratio: f64,
    /// Efficiency η (as printed, 2 decimals, when printed), 1.
    pub efficiency: f64,
    /// Whether the page prints η (`gear_efficiency`).
    pub efficiency_printed: bool,
}

impl Gear {
    /// A catalogue row at the motor shaft moved to the output shaft.
    pub fn output_row(&self, r: &TwinRow) -> TwinRow {
        let (g, eta) = (self.ratio, self.efficiency);
        TwinRow {
            free_speed_rad_s: r.free_speed_rad_s / g,
            max_power_w: eta * r.max_power_w,
            speed_at_max_power_rad_s: r.speed_at_max_power_rad_s / g,
            torque_at_max_power_nm: eta * g * r.torque_at_max_power_nm,
            stall_torque_nm: eta * g * r.stall_torque_nm,
            air_at_max_power_kg_s: r.air_at_max_power_kg_s,
            air_at_free_speed_kg_s: r.air_at_free_speed_kg_s,
        }
    }
}

/// How a styled page is printed.
#[derive(Debug, Clone, PartialEq)]
pub struct StyledPage {
    /// Its kind.
    pub kind: PageKind,
    /// Supply, units (of the figures and of the curves' columns), figures, curve cells and
    /// displacement, set as the kind says.
    pub style: PageStyle,
    /// The figures' units as printed (the makers' spellings on such a page, else
    /// `style.units`): speed, torque, power, air.
    pub figure_units: [PageUnit; 4],
    /// The gearbox of a geared page.
    pub gear: Option<Gear>,
    /// The second supply pressure (as printed, bar g) of a page that has one.
    pub second: Option<(&'static str, f64)>,
}

const RPM: f64 = 30.0 / std::f64::consts::PI;
/// N·m per ft·lbf: 4.4482216152605 N × 0.3048 m.
const NM_PER_FT_LBF: f64 = 4.448_221_615_260_5 * 0.3048;
/// N·m per kgf·m (standard gravity 9.80665 m/s², CGPM 1901).
const NM_PER_KGF_M: f64 = 9.806_65;
/// Density of normal air (DIN 1343: 101.325 kPa, 0 °C), kg/m³: the reference of Nl.
const RHO_NORMAL: f64 = 101_325.0 / (287.052_87 * 273.15);

/// Makers' spellings of the speed (German catalogues: U/min, min⁻¹).
pub const MAKER_SPEED_UNITS: [PageUnit; 2] = [
    PageUnit {
        printed: "U/min",
        column: "rpm",
        per_si: RPM,
    },
    PageUnit {
        printed: "min⁻¹",
        column: "rpm",
        per_si: RPM,
    },
];
/// Makers' spellings of the torque (US and Japanese catalogues).
pub const MAKER_TORQUE_UNITS: [PageUnit; 4] = [
    PageUnit {
        printed: "ft-lb",
        column: "nm",
        per_si: 1.0 / NM_PER_FT_LBF,
    },
    PageUnit {
        printed: "lb-ft",
        column: "nm",
        per_si: 1.0 / NM_PER_FT_LBF,
    },
    PageUnit {
        printed: "ft·lbf",
        column: "nm",
        per_si: 1.0 / NM_PER_FT_LBF,
    },
    PageUnit {
        printed: "kgf·m",
        column: "nm",
        per_si: 1.0 / NM_PER_KGF_M,
    },
];
/// Makers' spellings of the air consumption (normal litres).
pub const MAKER_AIR_UNITS: [PageUnit; 2] = [
    PageUnit {
        printed: "Nl/s",
        column: "l_s_anr",
        per_si: 1e3 / RHO_NORMAL,
    },
    PageUnit {
        printed: "Nl/min",
        column: "l_s_anr",
        per_si: 60e3 / RHO_NORMAL,
    },
];
/// Makers' spellings of the supply pressure, with its gauge value in bar.
pub const MAKER_SUPPLIES: [(&str, f64); 4] = [
    ("6.3 barg", 6.3),
    ("6 barg", 6.0),
    ("90 psig", 90.0 * 0.068_947_572_931_683_6),
    ("6 bar(ü)", 6.0),
];

/// The page of `kind` for motor seed `seed` (see the module documentation).
pub fn styled_page(seed: u64, kind: PageKind) -> StyledPage {
    let mut style = page_style(seed);
    let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed ^ 0x57e1_ed00_0000_0004);
    // The full page: curves, the six figures (the air at free speed as drawn), displacement.
    style.curve_points = style.curve_points.max(5);
    for k in 0..6 {
        style.figures[k] = true;
    }
    style.displacement = true;
    let mut page = StyledPage {
        kind,
        figure_units: style.units,
        style,
        gear: None,
        second: None,
    };
    match kind {
        PageKind::Full => {}
        PageKind::TableRow => {
            page.style.figures = [true, true, true, true, false, true, false];
            page.style.curve_points = 0;
            page.style.displacement = false;
        }
        PageKind::Geared => {
            let g = (3f64.ln() + rng.random::<f64>() * 10f64.ln()).exp();
            let eta: f64 = rng.random_range(0.85..=0.95);
            let printed = rng.random::<bool>();
            page.gear = Some(Gear {
                ratio: significant(g, 3).parse().unwrap(),
                efficiency: if printed {
                    (eta * 100.0).round() / 100.0
                } else {
                    eta
                },
                efficiency_printed: printed,
            });
        }
        PageKind::NoDisplacement => page.style.displacement = false,
        PageKind::SecondPressure => {
            page.second = Some(if page.style.supply.1 > 5.5 {
                ("4 bar(g)", 4.0)
            } else {
                ("7 bar(g)", 7.0)
            });
        }
        PageKind::MakersSpelling => {
            let pick = |rng: &mut Xoshiro256PlusPlus, n: usize| rng.random_range(0..n);
            page.style.supply = MAKER_SUPPLIES[pick(&mut rng, MAKER_SUPPLIES.len())];
            page.figure_units = [
                MAKER_SPEED_UNITS[pick(&mut rng, 2)],
                MAKER_TORQUE_UNITS[pick(&mut rng, 4)],
                page.style.units[2],
                MAKER_AIR_UNITS[pick(&mut rng, 2)],
            ];
        }
    }
    page
}

/// The twin's figures of `m` at `bar_g` at the page's output shaft, in [`FIGURES`] order, SI.
pub fn styled_row(m: &TwinMotor, page: &StyledPage, bar_g: f64) -> Result<TwinRow, String> {
    let c = Conditions {
        p_supply_pa: P_ATM_PA + bar_g * 1e5,
        ..Conditions::default()
    };
    let row = catalogue_row(m, &c)?;
    Ok(page.gear.map_or(row, |g| g.output_row(&row)))
}

/// The truth beside a page: the figures at each of `bar_g` at the page's output shaft.
pub fn styled_truth(
    m: &TwinMotor,
    page: &StyledPage,
    bar_g: &[f64],
) -> Result<Vec<[f64; 7]>, String> {
    bar_g
        .iter()
        .map(|b| styled_row(m, page, *b).map(|r| row_values(&r)))
        .collect()
}

/// The `[experiment.figures]` lines of `row` as `page` prints them.
fn figure_lines(page: &StyledPage, row: &TwinRow, printed: &[bool; 7]) -> String {
    let [speed, torque, power, air] = page.figure_units;
    let units = [speed, power, speed, torque, torque, air, air];
    let mut s = String::new();
    for (k, v) in row_values(row).iter().enumerate() {
        if printed[k] {
            let u = units[k];
            let value = significant(v * u.per_si, 3);
            writeln!(s, "{} = \"{value} {}\"", FIGURES[k], u.printed).unwrap();
        }
    }
    s
}

/// The `[motor]` table of a page.
fn motor_table(m: &TwinMotor, page: &StyledPage) -> String {
    let mut s = String::from("[motor]\nname = \"twin page motor\"\n");
    if page.style.displacement {
        let cm3 = significant(m.v_disp * 1e6, 2);
        writeln!(s, "displacement_m3 = {cm3}e-6").unwrap();
    }
    if let Some(g) = page.gear {
        writeln!(s, "gear_ratio = {}", g.ratio).unwrap();
        if g.efficiency_printed {
            writeln!(s, "gear_efficiency = {}", g.efficiency).unwrap();
        }
    }
    s
}

/// Writes `page` of motor `m` into `dir` (rig.toml and, with curves, curves.csv); returns
/// the row at the page's own supply (at its output shaft) or the twin's failure.
pub fn print_styled_page(dir: &Path, m: &TwinMotor, page: &StyledPage) -> Result<TwinRow, String> {
    let style = &page.style;
    let row = styled_row(m, page, style.supply.1)?;
    let mut toml = format!(
        "description = \"a maker's page, {} (tests/twin/styles.rs)\"\n\n{}",
        page.kind.name(),
        motor_table(m, page)
    );
    toml += "\n[[experiment]]\nkind = \"catalogue\"\n";
    if style.curve_points > 0 {
        toml += "file = \"curves.csv\"\n";
    }
    write!(
        toml,
        "p_supply = \"{}\"\n\n[experiment.figures]\n{}",
        style.supply.0,
        figure_lines(page, &row, &style.figures)
    )
    .unwrap();
    if let Some((printed, bar_g)) = page.second {
        let second = styled_row(m, page, bar_g)?;
        let figures = [true, true, true, true, true, true, false];
        write!(
            toml,
            "\n[[experiment]]\nkind = \"catalogue\"\np_supply = \"{printed}\"\n\n\
             [experiment.figures]\n{}",
            figure_lines(page, &second, &figures)
        )
        .unwrap();
    }
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    std::fs::write(dir.join("rig.toml"), toml).map_err(|e| e.to_string())?;
    if style.curve_points > 0 {
        let csv = styled_curves(m, page, &row)?;
        std::fs::write(dir.join("curves.csv"), csv).map_err(|e| e.to_string())?;
    }
    Ok(row)
}

/// The curves file at the page's output shaft: round output speeds from 0 below its free
/// speed, each cell printed by chance (at least one per row), 3 significant digits, in the
/// columns of `style.units`.
fn styled_curves(m: &TwinMotor, page: &StyledPage, row: &TwinRow) -> Result<String, String> {
    let style = &page.style;
    let c = Conditions {
        p_supply_pa: P_ATM_PA + style.supply.1 * 1e5,
        ..Conditions::default()
    };
    let (g, eta) = page.gear.map_or((1.0, 1.0), |g| (g.ratio, g.efficiency));
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
        let w_out = printed.parse::<f64>().unwrap() / RPM;
        let (t, q) = curve_point(m, &c, w_out * g)?;
        let (t_out, p_out) = (eta * g * t, eta * t * w_out * g);
        let mut cells = [0, 1, 2].map(|j| rng.random::<f64>() < style.cell_share[j]);
        if w_out == 0.0 {
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
            cell(cells[0], t_out * torque.per_si),
            cell(cells[1], p_out * power.per_si),
            cell(cells[2], q * air.per_si)
        )
        .unwrap();
    }
    Ok(out)
}
