//! `modelDescription.xml` of the FMU (FMI 2.0): the variables of [`super::variables`] with
//! units, descriptions and the fitted values as start values, the unit definitions (SI base
//! units) and the model structure (outputs, derivatives, initial unknowns).

use super::units::{base_unit, fmi_name};
use super::variables::{variables, Role, Variable, MODEL_IDENTIFIER};
use super::FmuError;
use crate::data::fitfile::FitFile;
use std::fmt::Write as _;

/// Escapes text for an XML attribute value.
fn esc(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for c in s.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            _ => out.push(c),
        }
    }
    out
}

/// The `<UnitDefinitions>` element: one `<Unit>` per distinct unit, with its SI base units.
fn unit_definitions(vars: &[Variable]) -> String {
    let mut names: Vec<(String, &str)> = Vec::new();
    for v in vars {
        if let Some(n) = fmi_name(&v.unit) {
            if !names.iter().any(|(m, _)| *m == n) {
                names.push((n, v.unit.as_str()));
            }
        }
    }
    let mut out = String::from("  <UnitDefinitions>\n");
    for (name, unit) in names {
        let _ = match base_unit(unit) {
            Some(b) => {
                let mut attrs = String::new();
                for (k, e) in [("kg", b.kg), ("m", b.m), ("s", b.s), ("rad", b.rad)] {
                    if e != 0 {
                        let _ = write!(attrs, " {k}=\"{e}\"");
                    }
                }
                writeln!(
                    out,
                    "    <Unit name=\"{}\"><BaseUnit{attrs}/></Unit>",
                    esc(&name)
                )
            }
            None => writeln!(out, "    <Unit name=\"{}\"/>", esc(&name)),
        };
    }
    out.push_str("  </UnitDefinitions>\n");
    out
}

/// One `<ScalarVariable>`; `index_of_state` gives the 1-based index of each state.
fn scalar_variable(v: &Variable, index_of_state: &[usize; 4]) -> String {
    let (causality, extra) = match v.role {
        Role::Input => ("input", " variability=\"continuous\""),
        Role::Output => ("output", " variability=\"continuous\""),
        Role::State => ("local", " variability=\"continuous\" initial=\"approx\""),
        Role::Derivative(_) => ("local", " variability=\"continuous\""),
        Role::Parameter => ("parameter", " variability=\"tunable\" initial=\"exact\""),
    };
    let mut attrs = String::new();
    if let Some(u) = fmi_name(&v.unit) {
        let _ = write!(attrs, " unit=\"{}\"", esc(&u));
    }
    if let Role::Derivative(k) = v.role {
        let _ = write!(attrs, " derivative=\"{}\"", index_of_state[k]);
    }
    let element = if v.boolean {
        let start = v.start.map_or(String::new(), |s| {
            format!(" start=\"{}\"", if s != 0.0 { "true" } else { "false" })
        });
        format!("<Boolean{start}/>")
    } else {
        if let Some(s) = v.start {
            let _ = write!(attrs, " start=\"{s:e}\"");
        }
        format!("<Real{attrs}/>")
    };
    format!(
        "    <ScalarVariable name=\"{}\" valueReference=\"{}\" causality=\"{causality}\"{extra} description=\"{}\">{element}</ScalarVariable>\n",
        esc(&v.name),
        v.vr,
        esc(&v.description)
    )
}

/// `<Unknown index=".."/>` lines for the 1-based indices of the variables that `pick`.
fn unknowns(vars: &[Variable], pick: impl Fn(&Variable) -> bool) -> String {
    vars.iter()
        .enumerate()
        .filter(|(_, v)| pick(v))
        .map(|(i, _)| format!("      <Unknown index=\"{}\"/>\n", i + 1))
        .collect()
}

/// The whole `modelDescription.xml` of the FMU of `fit`, under `guid`.
pub fn model_description(fit: &FitFile, guid: &str) -> Result<String, FmuError> {
    let vars = variables(fit)?;
    let mut index_of_state = [0; 4];
    for (i, v) in vars.iter().enumerate() {
        if v.role == Role::State {
            if let Some(k) = super::variables::vr::STATES.iter().position(|r| *r == v.vr) {
                index_of_state[k] = i + 1;
            }
        }
    }
    let effects = fit.effects.ids();
    let mut description = format!(
        "Pneumatic vane motor fitted by vanefit to dataset '{}'; effects: [{}]; discovered terms: {}",
        fit.dataset,
        effects.join(", "),
        fit.extra.len()
    );
    if let Some(g) = &fit.gear {
        description.push_str(&format!(
            "; geared: speed, torque and load are at the MOTOR shaft; the gearbox output turns {} times slower with {:.6} (efficiency times ratio) times the torque ({})",
            g.ratio,
            g.efficiency * g.ratio,
            g.describe()
        ));
    }
    let mut x = String::new();
    x.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n");
    let _ = writeln!(
        x,
        "<fmiModelDescription fmiVersion=\"2.0\" modelName=\"vanefit_motor\" guid=\"{}\" description=\"{}\" generationTool=\"vanefit {}\" numberOfEventIndicators=\"0\">",
        esc(guid),
        esc(&description),
        env!("CARGO_PKG_VERSION")
    );
    let _ = writeln!(
        x,
        "  <ModelExchange modelIdentifier=\"{MODEL_IDENTIFIER}\" canNotUseMemoryManagementFunctions=\"true\"/>"
    );
    let _ = writeln!(
        x,
        "  <CoSimulation modelIdentifier=\"{MODEL_IDENTIFIER}\" canHandleVariableCommunicationStepSize=\"true\" canInterpolateInputs=\"true\" canNotUseMemoryManagementFunctions=\"true\"/>"
    );
    x.push_str(&unit_definitions(&vars));
    x.push_str("  <DefaultExperiment startTime=\"0\" stopTime=\"1\" tolerance=\"1e-6\"/>\n");
    x.push_str("  <ModelVariables>\n");
    for v in &vars {
        x.push_str(&scalar_variable(v, &index_of_state));
    }
    x.push_str("  </ModelVariables>\n  <ModelStructure>\n    <Outputs>\n");
    x.push_str(&unknowns(&vars, |v| v.role == Role::Output));
    x.push_str("    </Outputs>\n    <Derivatives>\n");
    x.push_str(&unknowns(&vars, |v| matches!(v.role, Role::Derivative(_))));
    x.push_str("    </Derivatives>\n    <InitialUnknowns>\n");
    x.push_str(&unknowns(&vars, |v| {
        matches!(v.role, Role::Output | Role::State | Role::Derivative(_))
    }));
    x.push_str("    </InitialUnknowns>\n  </ModelStructure>\n</fmiModelDescription>\n");
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::gear::Gear;
    use crate::model::{EffectSet, MotorParams};

    /// A geared fit's FMU says its speed, torque and load are the motor shaft's; an
    /// ungeared one says nothing of shafts.
    #[test]
    fn a_geared_fmu_names_the_motor_shaft() {
        let mut fit = FitFile::from_params("g", MotorParams::default(), EffectSet::empty());
        let plain = model_description(&fit, "id").unwrap();
        assert!(!plain.contains("shaft;") && !plain.contains("MOTOR"));
        fit.gear = Some(Gear::new(4.0, Some(0.9)));
        let geared = model_description(&fit, "id").unwrap();
        assert!(geared.contains("geared: speed, torque and load are at the MOTOR shaft"));
        for name in ["speed", "torque_shaft", "t_load", "c_brake", "omega"] {
            let line = geared
                .lines()
                .find(|l| l.contains(&format!("name=\"{name}\"")))
                .unwrap();
            assert!(
                line.contains("MOTOR shaft; gearbox output: speed/4"),
                "{line}"
            );
        }
    }
}
