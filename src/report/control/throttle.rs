//! Tables and figure of `throttle-inlet` / `throttle-outlet` (paper Figs. 14, 15):
//! `throttle_<port>_speed.csv`, `throttle_<port>_torque_speed.csv`, `throttle_<port>.svg`.
//!
//! The throttle's conductance is written in m³/(s·Pa) (first column, as before) and, as
//! catalogues and ISO 6358 give it, in dm³/(s·bar) (last column, `c_port<n>_dm3_s_bar`).

use super::{describe_load, ControlReportError, Table, Writer};
use crate::control::rpm;
use crate::control::study::throttle::ThrottleStudy;
use crate::control::throttle::Port;
use crate::model::params::conductance_dm3_s_bar;
use crate::report::explain;
use crate::report::plot::{Chart, Figure, Legend, Series};

/// Writes the tables and the figure of a throttling study.
pub fn write(w: &mut Writer, r: &ThrottleStudy) -> Result<(), ControlReportError> {
    let port = r.settings.port();
    let (c_col, c_catalogue) = match port {
        Port::Inlet => ("c_port1_m3_s_pa", "c_port1_dm3_s_bar"),
        Port::Outlet => ("c_port2_m3_s_pa", "c_port2_dm3_s_bar"),
    };
    let mut t = Table::new(&[
        c_col,
        "speed_rpm",
        "torque_nm",
        "flow1_g_s",
        "p1_mpa",
        c_catalogue,
    ]);
    for p in &r.speed {
        t.push(vec![
            p.c_m3_s_pa,
            rpm(p.speed_rad_s),
            p.torque_nm,
            p.flow_kg_s * 1e3,
            p.p1_pa / 1e6,
            conductance_dm3_s_bar(p.c_m3_s_pa),
        ]);
    }
    let stem = format!("throttle_{}", port.name());
    w.csv(&format!("{stem}_speed.csv"), &t)?;
    let mut tq = Table::new(&[c_col, "speed_rpm", "torque_nm", "flow1_g_s", c_catalogue]);
    for curve in &r.curves {
        for p in &curve.points {
            // No throttle is written as conductance 0 in the table.
            let c = curve.c_m3_s_pa.unwrap_or(0.0);
            tq.push(vec![
                c,
                rpm(p.speed_rad_s),
                p.torque_nm,
                p.flow_kg_s * 1e3,
                conductance_dm3_s_bar(c),
            ]);
        }
    }
    w.csv(&format!("{stem}_torque_speed.csv"), &tq)?;
    w.figure(
        &format!("{stem}.svg"),
        &Figure::new(vec![speed_chart(r), torque_chart(r)], 2),
    )
}

/// Steady speed against throttle conductance (Fig. 14).
fn speed_chart(r: &ThrottleStudy) -> Chart {
    let port = r.settings.port();
    let mut chart = Chart::new(
        &format!(
            "Steady speed vs {} throttle ({} MPa, {})",
            port.name(),
            r.settings.p_supply_mpa(),
            describe_load(&r.load)
        ),
        &format!(
            "{} throttle conductance [m3/(s*Pa)]; 1e-8 m3/(s*Pa) = 1 dm3/(s*bar)",
            port.name()
        ),
        "speed [rpm]",
    )
    .log_x()
    .legend(Legend::Right)
    .with(Series::line(
        "speed",
        r.speed
            .iter()
            .map(|p| (p.c_m3_s_pa, rpm(p.speed_rad_s)))
            .collect(),
    ));
    chart.y_range = Some((
        0.0,
        1.05 * rpm(r.speed.iter().map(|p| p.speed_rad_s).fold(0.0, f64::max)).max(1.0),
    ));
    chart
}

/// Shaft torque against speed for each throttle (Fig. 15).
fn torque_chart(r: &ThrottleStudy) -> Chart {
    let mut chart = Chart::new(
        &format!("Torque vs speed, {} throttles", r.settings.port().name()),
        "speed [rpm]",
        "shaft torque [N*m]",
    );
    chart.series = r
        .curves
        .iter()
        .map(|curve| {
            let name = curve.c_m3_s_pa.map_or("no throttle".to_string(), |c| {
                format!("C = {}", explain::conductance(c, 3))
            });
            Series::line(
                &name,
                curve
                    .points
                    .iter()
                    .map(|p| (rpm(p.speed_rad_s), p.torque_nm))
                    .collect(),
            )
        })
        .collect();
    chart
}
