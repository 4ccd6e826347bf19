//! Tables and figure of `throttle-inlet` / `throttle-outlet` (paper Figs. 14, 15):
//! `throttle_<port>_speed.csv`, `throttle_<port>_torque_speed.csv`, `throttle_<port>.svg`.

use super::{describe_load, ControlReportError, Table, Writer};
use crate::control::rpm;
use crate::control::study::throttle::ThrottleStudy;
use crate::control::throttle::Port;
use crate::report::plot::{Chart, Figure, Legend, Series};

/// Writes the tables and the figure of a throttling study.
pub fn write(w: &mut Writer, r: &ThrottleStudy) -> Result<(), ControlReportError> {
    let port = r.settings.port();
    let c_col = match port {
        Port::Inlet => "c_port1_m3_s_pa",
        Port::Outlet => "c_port2_m3_s_pa",
    };
    let mut t = Table::new(&[c_col, "speed_rpm", "torque_nm", "flow1_g_s", "p1_mpa"]);
    for p in &r.speed {
        t.push(vec![
            p.c_m3_s_pa,
            rpm(p.speed_rad_s),
            p.torque_nm,
            p.flow_kg_s * 1e3,
            p.p1_pa / 1e6,
        ]);
    }
    let stem = format!("throttle_{}", port.name());
    w.csv(&format!("{stem}_speed.csv"), &t)?;
    let mut tq = Table::new(&[c_col, "speed_rpm", "torque_nm", "flow1_g_s"]);
    for curve in &r.curves {
        for p in &curve.points {
            // No throttle is written as conductance 0 in the table.
            tq.push(vec![
                curve.c_m3_s_pa.unwrap_or(0.0),
                rpm(p.speed_rad_s),
                p.torque_nm,
                p.flow_kg_s * 1e3,
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
        &format!("{} throttle conductance [m3/(s*Pa)]", port.name()),
        "speed [rpm]",
    )
    .log_x()
    .legend(Legend::LowerRight)
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
            let name = curve
                .c_m3_s_pa
                .map_or("no throttle".to_string(), |c| format!("C = {c:.2e}"));
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
