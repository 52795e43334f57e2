//! modelDescription.xml, written from the interface table (modelDescription/variables.toml).
//! Written by hand rather than by a schema crate so that no empty `<Derivatives/>` or
//! `<InitialUnknowns/>` element appears (fmpy's validator rejects them).

use gearfmu::interface::{Start, Variable};
use std::fmt::Write;

/// Per-FMU facts that the interface table leaves to the model.
pub struct ModelFacts<'a> {
    pub model_name: &'a str,
    pub guid: &'a str,
    pub description: &'a str,
    /// Start values for variables whose start is "model".
    pub model_starts: &'a [(&'a str, f64)],
    /// A gear pair's torque on gear 1 it was built for and the one where a tooth root yields
    /// (N·m): written as the tool's vendor annotation, so a master or a sweep can default to it.
    /// None for a drivetrain element.
    pub operating_point_nm: Option<(f64, f64)>,
    /// The DefaultExperiment's communication step (s).
    pub default_step_s: f64,
}

pub const MODEL_IDENTIFIER: &str = "gearfmu";

fn escape(text: &str) -> String {
    text.replace('&', "&amp;").replace('<', "&lt;").replace('>', "&gt;").replace('"', "&quot;")
}

/// SI base-unit exponents of each unit used in the interface.
fn base_units(unit: &str) -> &'static str {
    match unit {
        "N.m" => r#"kg="1" m="2" s="-2""#,
        "N.m/rad" => r#"kg="1" m="2" s="-2" rad="-1""#,
        "N.m.s/rad" => r#"kg="1" m="2" s="-1" rad="-1""#,
        "N.m.s2/rad2" => r#"kg="1" m="2" rad="-2""#,
        "N" => r#"kg="1" m="1" s="-2""#,
        "N/m" => r#"kg="1" s="-2""#,
        "m" => r#"m="1""#,
        "s" => r#"s="1""#,
        "rad" => r#"rad="1""#,
        "rad/s" => r#"rad="1" s="-1""#,
        "kg.m2" => r#"kg="1" m="2""#,
        "m/s" => r#"m="1" s="-1""#,
        "W" => r#"kg="1" m="2" s="-3""#,
        "J" => r#"kg="1" m="2" s="-2""#,
        "mPa.s" => r#"kg="1" m="-1" s="-1" factor="0.001""#,
        "um" => r#"m="1" factor="1e-06""#,
        _ => "",
    }
}

pub fn write(variables: &[Variable], facts: &ModelFacts) -> Result<String, String> {
    let mut x = String::new();
    let w = &mut x;
    writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#).unwrap();
    writeln!(
        w,
        r#"<fmiModelDescription fmiVersion="2.0" modelName="{}" guid="{}" description="{}" generationTool="gearfmu fmu-build {}" variableNamingConvention="flat" numberOfEventIndicators="0">"#,
        escape(facts.model_name),
        facts.guid,
        escape(facts.description),
        env!("CARGO_PKG_VERSION")
    )
    .unwrap();
    writeln!(
        w,
        r#"  <CoSimulation modelIdentifier="{MODEL_IDENTIFIER}" canHandleVariableCommunicationStepSize="true" canGetAndSetFMUstate="true" canSerializeFMUstate="true" canNotUseMemoryManagementFunctions="true" canInterpolateInputs="false" maxOutputDerivativeOrder="0" providesDirectionalDerivative="false"/>"#
    )
    .unwrap();
    let mut units: Vec<&str> = variables.iter().filter_map(|v| v.unit.as_deref()).collect();
    units.sort();
    units.dedup();
    writeln!(w, "  <UnitDefinitions>").unwrap();
    for u in &units {
        writeln!(w, r#"    <Unit name="{u}"><BaseUnit {}/></Unit>"#, base_units(u)).unwrap();
    }
    writeln!(w, "  </UnitDefinitions>").unwrap();
    writeln!(w, "  <LogCategories>").unwrap();
    for c in gearfmu::fmi2::instance::LOG_CATEGORIES {
        writeln!(w, r#"    <Category name="{c}"/>"#).unwrap();
    }
    writeln!(w, "  </LogCategories>").unwrap();
    writeln!(w, r#"  <DefaultExperiment startTime="0" stopTime="0.025" stepSize="{:?}"/>"#, facts.default_step_s)
        .unwrap();
    // FMI 2.0's place for a tool's own data (§2.2.6): read by gearfmu.sweep for its defaults.
    if let Some((operating, yielding)) = facts.operating_point_nm {
        writeln!(
            w,
            r#"  <VendorAnnotations><Tool name="gearfmu"><OperatingPoint torque_1="{operating:?}" yield_torque_1="{yielding:?}" unit="N.m"/></Tool></VendorAnnotations>"#,
        )
        .unwrap();
    }
    writeln!(w, "  <ModelVariables>").unwrap();
    let mut outputs = Vec::new();
    for (index, v) in variables.iter().enumerate() {
        let (variability, initial) = match (v.causality.as_str(), v.kind.as_str()) {
            ("input", _) => ("continuous", ""),
            ("output", "Integer") => ("discrete", r#" initial="calculated""#),
            ("output", _) => ("continuous", r#" initial="calculated""#),
            ("parameter", _) => ("fixed", r#" initial="exact""#),
            (c, _) => return Err(format!("variable {}: unsupported causality {c}", v.name)),
        };
        if v.causality == "output" {
            outputs.push(index + 1);
        }
        let start = match &v.start {
            None => String::new(),
            Some(Start::Value(s)) => format!(r#" start="{s:?}""#),
            Some(Start::Flag(b)) => format!(r#" start="{b}""#),
            Some(Start::FromModel(tag)) if tag == "model" => {
                let value = facts
                    .model_starts
                    .iter()
                    .find(|(n, _)| *n == v.name)
                    .ok_or_else(|| format!("variable {}: start = \"model\" but the model gives none", v.name))?
                    .1;
                format!(r#" start="{value:?}""#)
            }
            Some(Start::FromModel(other)) => {
                return Err(format!("variable {}: start = \"{other}\" is not a number or \"model\"", v.name))
            }
        };
        let unit = v.unit.as_deref().map(|u| format!(r#" unit="{u}""#)).unwrap_or_default();
        writeln!(
            w,
            r#"    <ScalarVariable name="{}" valueReference="{}" causality="{}" variability="{variability}"{initial} description="{}"><{}{unit}{start}/></ScalarVariable>"#,
            v.name,
            v.value_reference,
            v.causality,
            escape(&v.description),
            v.kind
        )
        .unwrap();
    }
    writeln!(w, "  </ModelVariables>").unwrap();
    // An output depends directly only on the inputs its depends_on lists: none for the gear pair
    // and the bodies (the torques act through a doStep's integration), dependencies="" (without
    // it FMI 2.0 means "on every input", which makes masters report algebraic loops); the
    // shaft's torques on its flanges' angles and speeds. At initialization each output lists
    // what it is computed from (initial_depends_on), by index.
    let index_of = |name: &str| -> Result<usize, String> {
        variables.iter().position(|v| v.name == name).map(|i| i + 1).ok_or_else(|| format!("unknown variable {name}"))
    };
    writeln!(w, "  <ModelStructure>").unwrap();
    writeln!(w, "    <Outputs>").unwrap();
    for &i in &outputs {
        let v = &variables[i - 1];
        let mut indices = Vec::new();
        for name in v.depends_on.iter().flatten() {
            let j = index_of(name).map_err(|e| format!("output {}: depends_on: {e}", v.name))?;
            if variables[j - 1].causality != "input" {
                return Err(format!("output {}: depends_on lists {name}, which is not an input", v.name));
            }
            indices.push(j);
        }
        indices.sort();
        let list: Vec<String> = indices.iter().map(|j| j.to_string()).collect();
        writeln!(w, r#"      <Unknown index="{i}" dependencies="{}"/>"#, list.join(" ")).unwrap();
    }
    writeln!(w, "    </Outputs>").unwrap();
    writeln!(w, "    <InitialUnknowns>").unwrap();
    for &i in &outputs {
        let v = &variables[i - 1];
        let names = v.initial_depends_on.as_ref().ok_or_else(|| {
            format!("output {}: variables.toml gives no initial_depends_on (what its initial value depends on)", v.name)
        })?;
        let mut indices = Vec::with_capacity(names.len());
        for name in names {
            let j = index_of(name).map_err(|e| format!("output {}: initial_depends_on: {e}", v.name))?;
            if !matches!(variables[j - 1].causality.as_str(), "input" | "parameter") {
                return Err(format!(
                    "output {}: initial_depends_on lists {name}, neither an input nor a parameter",
                    v.name
                ));
            }
            indices.push(j);
        }
        indices.sort();
        let list: Vec<String> = indices.iter().map(|j| j.to_string()).collect();
        writeln!(w, r#"      <Unknown index="{i}" dependencies="{}"/>"#, list.join(" ")).unwrap();
    }
    writeln!(w, "    </InitialUnknowns>").unwrap();
    writeln!(w, "  </ModelStructure>").unwrap();
    writeln!(w, "</fmiModelDescription>").unwrap();
    Ok(x)
}

#[cfg(test)]
mod tests {
    use super::*;
    use fmi_schema::fmi2::{Causality, Fmi2ModelDescription};
    use gearfmu::fmu::gear_pair::Var;

    fn xml() -> String {
        let starts = [
            ("inertia_1", 1.0),
            ("inertia_2", 2.0),
            ("mesh_damping_ratio", 0.05),
            ("max_step", 1e-5),
            ("friction_coefficient", 0.05),
            ("oil_viscosity", 0.0),
            ("flank_roughness_ra", 0.0),
            ("lubricant_factor", 1.0),
        ];
        let facts = ModelFacts {
            model_name: "Test",
            guid: "{x}",
            description: "d",
            model_starts: &starts,
            operating_point_nm: Some((250.0, 1000.0)),
            default_step_s: 1e-5,
        };
        write(gearfmu::interface::variables(), &facts).unwrap()
    }

    /// The value references the FMU binary answers to (its name → physics map, built from
    /// variables.toml) are the ones modelDescription.xml declares, read back by an independent
    /// parser; every variable has physics, and Outputs lists exactly the outputs.
    #[test]
    fn value_references_in_rust_and_xml_agree() {
        let md: Fmi2ModelDescription = fmi_schema::deserialize(&xml()).unwrap();
        let vars = &md.model_variables.variables;
        assert_eq!(vars.len(), Var::ALL.len());
        for var in Var::ALL {
            let in_xml = vars.iter().find(|v| v.name == var.name()).unwrap_or_else(|| panic!("{} missing", var.name()));
            assert_eq!(Some(in_xml.value_reference), gearfmu::interface::value_reference(var.name()));
        }
        let mut refs: Vec<_> = vars.iter().map(|v| v.value_reference).collect();
        refs.sort();
        refs.dedup();
        assert_eq!(refs.len(), vars.len(), "value references are unique");
        let outputs: Vec<usize> = md.model_structure.outputs.unknowns.iter().map(|u| u.index as usize).collect();
        let expected: Vec<usize> =
            vars.iter().enumerate().filter(|(_, v)| v.causality == Causality::Output).map(|(i, _)| i + 1).collect();
        assert_eq!(outputs, expected);
        assert_eq!(md.co_simulation.unwrap().model_identifier, MODEL_IDENTIFIER);
    }

    /// The ModelStructure read back by an independent parser (issue 29): no output depends on an
    /// input during stepping (dependencies=""), nor in Initialization Mode, where the outputs
    /// are those of the start values (parameters only: the C-API test
    /// `outputs_do_not_follow_the_torques_until_a_step` checks the binary does as declared).
    #[test]
    fn model_structure_declares_no_direct_feedthrough_and_the_initial_dependencies() {
        let text = xml();
        let md: Fmi2ModelDescription = fmi_schema::deserialize(&text).unwrap();
        let vars = &md.model_variables.variables;
        let index = |name: &str| vars.iter().position(|v| v.name == name).unwrap() as u32 + 1;
        let outputs = &md.model_structure.outputs.unknowns;
        assert!(!outputs.is_empty());
        // The parser reads an absent and an empty list alike; the attribute itself must be there
        // (absent means "depends on every input").
        let section = text.split("<Outputs>").nth(1).unwrap().split("</Outputs>").next().unwrap();
        for u in outputs {
            let declared = format!(r#"<Unknown index="{}" dependencies=""/>"#, u.index);
            assert!(section.contains(&declared), "output {} must declare dependencies=\"\": {section}", u.index);
        }
        let initial = &md.model_structure.initial_unknowns.unknowns;
        assert_eq!(initial.len(), outputs.len());
        let deps =
            |name: &str| -> Vec<u32> { initial.iter().find(|u| u.index == index(name)).unwrap().dependencies.clone() };
        for u in initial {
            assert!(!u.dependencies.is_empty(), "initial unknown {} lists what it depends on", u.index);
            for &j in &u.dependencies {
                let c = &vars[j as usize - 1].causality;
                assert_eq!(*c, Causality::Parameter, "initial unknown {}: {j} is not a parameter", u.index);
            }
        }
        for angle_like in ["phi_1", "phi_2", "dte", "mesh_force", "contact_pairs"] {
            assert!(deps(angle_like).contains(&index("phi_1_start")), "{angle_like}");
        }
        for speed in ["w_1", "w_2"] {
            assert!(deps(speed).contains(&index("w_2_start")), "{speed}");
        }
    }

    #[test]
    fn a_model_start_without_a_value_is_an_error() {
        let facts = ModelFacts {
            model_name: "T",
            guid: "{x}",
            description: "d",
            model_starts: &[],
            operating_point_nm: Some((250.0, 1000.0)),
            default_step_s: 1e-5,
        };
        let e = write(gearfmu::interface::variables(), &facts).unwrap_err();
        // The first variable whose start the model must give (in variables.toml order).
        assert!(e.contains("max_step") && e.contains("start = \"model\""), "{e}");
    }
}
