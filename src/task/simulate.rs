//! `simulate` as a task: the motor of a dataset under a fit file, every experiment of the
//! dataset simulated with it, and the tables `vanefit simulate` writes (the recording's
//! inputs as recorded, then the simulated outputs in the recording's units).

use crate::data::dataset::{Cells, DataError, Dataset, Kind};
use crate::data::fitfile::FitFile;
use crate::model::effects::EffectSet;
use crate::model::motor::Motor;
use crate::model::params::MotorParams;
use crate::numerics::DefaultSolver;
use crate::sim::experiment::{Experiment, SimError};
use crate::units::Quantity;
use std::path::{Path, PathBuf};

/// Why a simulation, or writing what it made, failed (`simulate`'s tables, `synth`'s
/// dataset and truth file).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimulateError {
    /// The dataset has no nominal motor.
    #[error(transparent)]
    Data(#[from] DataError),
    /// An experiment cannot be simulated.
    #[error(transparent)]
    Sim(#[from] SimError),
    /// A file cannot be written.
    #[error("{}: {source}", path.display())]
    Write {
        /// The file (for a truth file, its dataset folder).
        path: PathBuf,
        /// What went wrong.
        source: std::io::Error,
    },
}

/// Parameters for a dataset: the fit file's, or else the rig's nominal motor.
fn params_for(ds: &Dataset, fit: Option<&FitFile>) -> Result<(MotorParams, EffectSet), DataError> {
    if let Some(f) = fit {
        return Ok((f.params.clone(), f.effects.clone()));
    }
    Ok((ds.nominal_params()?, EffectSet::empty()))
}

/// The motor of a dataset under an optional fit file (its parameters, effects and
/// discovered terms; without one the rig's nominal motor).
pub fn motor_for(ds: &Dataset, fit: Option<&FitFile>) -> Result<Motor, DataError> {
    let (p, effects) = params_for(ds, fit)?;
    let extra = fit.map(|f| f.extra.clone()).unwrap_or_default();
    Ok(Motor::new(p, effects).with_extra(&extra))
}

/// One column of a simulated recording: the recording's column name (with its unit) and
/// the values in that unit; `raw` holds an input column's cells exactly as recorded.
#[derive(Debug, Clone)]
pub struct SimulatedColumn {
    /// The recording's column name, unit included.
    pub name: String,
    /// Values in the column's unit (an input's as recorded, NaN for an empty cell).
    pub values: Vec<f64>,
    /// An input column's cells as recorded (`None` for a simulated output).
    pub raw: Option<Cells>,
}

/// A recording simulated as `vanefit simulate` writes it: the inputs as recorded, then
/// every simulated output that the recording has, in the recording's units, same rows.
#[derive(Debug, Clone)]
pub struct SimulatedTable {
    /// The recording's file name.
    pub file: String,
    /// Inputs first, then outputs.
    pub columns: Vec<SimulatedColumn>,
}

/// Every experiment of `ds` simulated with `motor` (the tables `vanefit simulate` writes).
pub fn simulated_tables(ds: &Dataset, motor: &Motor) -> Result<Vec<SimulatedTable>, SimError> {
    let solver = DefaultSolver::default();
    let mut out = Vec::new();
    for data in &ds.experiments {
        let sim = Experiment::new(data, ds.p_atm_pa)?.simulate(motor, &solver)?;
        let rec = &data.recording;
        let inputs: &[Quantity] = match data.kind {
            Kind::Datasheet | Kind::Catalogue => {
                &[Quantity::Time, Quantity::Speed, Quantity::PPort1]
            }
            _ => &[Quantity::Time, Quantity::PPort1, Quantity::CPort2],
        };
        let mut columns: Vec<SimulatedColumn> = rec
            .columns
            .iter()
            .filter(|c| inputs.contains(&c.quantity))
            .map(|c| SimulatedColumn {
                name: c.name.clone(),
                values: c
                    .raw
                    .iter()
                    .map(|v| v.trim().parse().unwrap_or(f64::NAN))
                    .collect(),
                raw: Some(c.raw.clone()),
            })
            .collect();
        for c in rec.columns.iter().filter(|c| !inputs.contains(&c.quantity)) {
            if let Some(v) = sim.channel(c.quantity) {
                columns.push(SimulatedColumn {
                    name: c.name.clone(),
                    values: v.iter().map(|x| c.unit.from_si(*x, ds.p_atm_pa)).collect(),
                    raw: None,
                });
            }
        }
        out.push(SimulatedTable {
            file: data.file.clone(),
            columns,
        });
    }
    Ok(out)
}

/// Writes `table` as CSV into the folder `dir` (atomically), under the recording's file
/// name: inputs as recorded, outputs with 7 significant digits. Returns the file's path.
pub fn write_table(table: &SimulatedTable, dir: &Path) -> Result<PathBuf, SimulateError> {
    let header: Vec<&str> = table.columns.iter().map(|c| c.name.as_str()).collect();
    let mut text = header.join(",") + "\n";
    // Inputs as recorded, outputs formatted row by row (not gathered first: a column of
    // cells holds at most 4 GiB of text, and the outputs need not be held twice).
    let rows = table.columns.first().map_or(0, |c| c.values.len());
    for r in 0..rows {
        let row: Vec<String> = table
            .columns
            .iter()
            .map(|c| match &c.raw {
                Some(raw) => raw[r].to_string(),
                None => format!("{:.6e}", c.values[r]),
            })
            .collect();
        text.push_str(&row.join(","));
        text.push('\n');
    }
    let path = dir.join(&table.file);
    crate::io::write_atomic(&path, text.as_bytes()).map_err(|source| SimulateError::Write {
        path: path.clone(),
        source,
    })?;
    Ok(path)
}
