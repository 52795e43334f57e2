//! The drivetrain around the gear pair (issue 29): the element FMUs (`fmu-build element`) and
//! the SSP system motor → shaft → gear pair → shaft → load (`fmu-build ssp`), which libcosim,
//! fmpy and the commercial masters load as one file.
//!
//! The SSP archive holds SystemStructure.ssd and the five FMUs under resources/. Every
//! connection is a plain equality: the gear FMU counts each gear's angle, speed and torque in
//! its own mesh sense, and so the motor is counted in gear 1's sense and the load in gear 2's
//! (the physical counter-rotation of the two shafts is folded into that convention).

use crate::model_description::{self, ModelFacts};
use anyhow::{Context, Result};
use clap::{Args, ValueEnum};
use gearfmu::drivetrain::elements::{Element, SpeedTorqueCurve};
use gearfmu::model_file::{ModelFile, ModelKind};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

/// The communication step the SSP file declares (s). In Jacobi coupling a massless shaft's
/// torque reaches a body two steps after the angles it is made of; on the demo drivetrain
/// (gear 1 on shaft 1 at ≈ 2.7·10³ rad/s) that explicit loop diverges between 6·10⁻⁵ and
/// 7·10⁻⁵ s (measured in libcosim, 0.5 s runs), so the file declares 2.5·10⁻⁵ s, a margin of
/// 2.4 (`tests/python/test_ssp_drivetrain.py` runs it at twice this step too).
pub const SSP_COMMUNICATION_STEP_S: f64 = 2.5e-5;

#[derive(Clone, Copy, ValueEnum)]
pub enum ElementKind {
    Inertia,
    Shaft,
    Motor,
    Load,
}

/// One element's parameters (the build's start values; a master may set others).
#[derive(Args, Clone)]
pub struct ElementOptions {
    /// Moment of inertia (kg·m²): inertia, motor rotor, load.
    #[arg(long, default_value_t = 0.05)]
    pub inertia_kgm2: f64,
    /// Shaft stiffness (N·m/rad).
    #[arg(long, default_value_t = 2.0e4)]
    pub stiffness_nm_per_rad: f64,
    /// Shaft damping (N·m·s/rad).
    #[arg(long, default_value_t = 2.0)]
    pub damping_nms_per_rad: f64,
    /// Motor: the torque of the ramp's end (N·m).
    #[arg(long, default_value_t = 200.0, allow_negative_numbers = true)]
    pub final_torque_nm: f64,
    /// Motor: the haversine ramp's duration (s).
    #[arg(long, default_value_t = 0.02)]
    pub ramp_time_s: f64,
    /// Motor: a speed–torque curve, CSV rows "speed_rad_s,torque_nm" (ascending speeds); the
    /// drive is then final_torque × ramp × curve(ω) / its peak.
    #[arg(long)]
    pub speed_torque_csv: Option<PathBuf>,
    /// Load: viscous torque per unit speed (N·m·s/rad).
    #[arg(long, default_value_t = 2.0)]
    pub viscous_nms_per_rad: f64,
    /// Load: quadratic torque per unit speed squared (N·m·s²/rad²).
    #[arg(long, default_value_t = 0.0)]
    pub quadratic_nms2_per_rad2: f64,
    /// Load: constant resisting torque (N·m).
    #[arg(long, default_value_t = 0.0, allow_negative_numbers = true)]
    pub constant_nm: f64,
    /// Bodies: the longest internal RK4 step (s).
    #[arg(long, default_value_t = 1e-4)]
    pub max_step_s: f64,
}

impl ElementOptions {
    pub fn element(&self, kind: ElementKind) -> Result<Element> {
        let curve = match &self.speed_torque_csv {
            None => None,
            Some(path) => Some(read_curve(path)?),
        };
        let element = match kind {
            ElementKind::Inertia => Element::Inertia { inertia_kgm2: self.inertia_kgm2, max_step_s: self.max_step_s },
            ElementKind::Shaft => Element::Shaft {
                stiffness_nm_per_rad: self.stiffness_nm_per_rad,
                damping_nms_per_rad: self.damping_nms_per_rad,
            },
            ElementKind::Motor => Element::Motor {
                inertia_kgm2: self.inertia_kgm2,
                final_torque_nm: self.final_torque_nm,
                ramp_time_s: self.ramp_time_s,
                curve,
                max_step_s: self.max_step_s,
            },
            ElementKind::Load => Element::Load {
                inertia_kgm2: self.inertia_kgm2,
                viscous_nms_per_rad: self.viscous_nms_per_rad,
                quadratic_nms2_per_rad2: self.quadratic_nms2_per_rad2,
                constant_nm: self.constant_nm,
                max_step_s: self.max_step_s,
            },
        };
        element.check().map_err(anyhow::Error::msg)?;
        Ok(element)
    }
}

fn read_curve(path: &Path) -> Result<SpeedTorqueCurve> {
    let text = std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let (mut speed, mut torque) = (Vec::new(), Vec::new());
    for (i, line) in text.lines().enumerate().filter(|(_, l)| !l.trim().is_empty() && !l.starts_with('#')) {
        let fields: Vec<&str> = line.split(',').map(str::trim).collect();
        let parsed: Option<Vec<f64>> = fields.iter().map(|f| f.parse().ok()).collect();
        match parsed.as_deref() {
            Some([w, t]) => {
                speed.push(*w);
                torque.push(*t);
            }
            _ if i == 0 => continue, // a header
            _ => anyhow::bail!("{} line {}: expected \"speed_rad_s,torque_nm\", got {line:?}", path.display(), i + 1),
        }
    }
    SpeedTorqueCurve::new(speed, torque).map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))
}

/// One element FMU, as the bytes of its archive.
pub fn element_fmu(name: &str, element: Element, so: &[u8]) -> Result<Vec<u8>> {
    let kind = ModelKind::Element(element.clone());
    let guid = ModelFile::compute_guid(gearfmu::drivetrain::elements::ELEMENTS_TOML, name, &kind);
    let starts = element.parameter_starts();
    let description = match &element {
        Element::Inertia { .. } => "Rigid inertia with a torque at each flange (MSL Rotational signs)".to_string(),
        Element::Shaft { .. } => "Massless torsional spring–damper between two flanges (MSL SpringDamper)".to_string(),
        Element::Motor { curve, .. } => format!(
            "Motor: rotor inertia driven by a haversine torque ramp{}",
            if curve.is_some() { " times a speed–torque curve" } else { "" }
        ),
        Element::Load { .. } => "Load: inertia braked by viscous, quadratic and constant torques".to_string(),
    };
    let xml = model_description::write(
        element.variables(),
        &ModelFacts {
            model_name: name,
            guid: &guid,
            description: &description,
            model_starts: &starts,
            operating_point_nm: None,
            default_step_s: SSP_COMMUNICATION_STEP_S,
        },
    )
    .map_err(anyhow::Error::msg)?;
    let file = ModelFile { guid, pair_name: name.to_string(), model: kind };
    crate::fmu_archive::fmu_archive(&xml, &file, so)
}

/// The demo drivetrain's elements (examples/drivetrain.py's defaults).
#[derive(Args, Clone)]
pub struct DrivetrainOptions {
    #[arg(long, default_value_t = 0.05)]
    pub motor_inertia_kgm2: f64,
    #[arg(long, default_value_t = 200.0)]
    pub motor_torque_nm: f64,
    #[arg(long, default_value_t = 0.02)]
    pub motor_ramp_s: f64,
    #[arg(long, default_value_t = 2.0e4)]
    pub shaft_1_stiffness_nm_per_rad: f64,
    #[arg(long, default_value_t = 2.0)]
    pub shaft_1_damping_nms_per_rad: f64,
    #[arg(long, default_value_t = 4.0e4)]
    pub shaft_2_stiffness_nm_per_rad: f64,
    #[arg(long, default_value_t = 4.0)]
    pub shaft_2_damping_nms_per_rad: f64,
    #[arg(long, default_value_t = 0.2)]
    pub load_inertia_kgm2: f64,
    #[arg(long, default_value_t = 2.0)]
    pub load_viscous_nms_per_rad: f64,
    /// The bodies' internal RK4 step (s).
    #[arg(long, default_value_t = SSP_COMMUNICATION_STEP_S, allow_negative_numbers = true, value_parser = crate::cli_values::positive_number)]
    pub max_step_s: f64,
    /// The communication step the file declares (s).
    #[arg(long, default_value_t = SSP_COMMUNICATION_STEP_S, allow_negative_numbers = true, value_parser = crate::cli_values::positive_number)]
    pub communication_step_s: f64,
    /// The stop time the file declares (s).
    #[arg(long, default_value_t = 0.5, allow_negative_numbers = true, value_parser = crate::cli_values::positive_number)]
    pub stop_time_s: f64,
}

/// A component of the system: its name, FMU file name, element (None: the gear pair) and its
/// connectors (name, kind).
struct Component {
    name: &'static str,
    element: Option<Element>,
    connectors: &'static [(&'static str, &'static str)],
}

const GEAR_CONNECTORS: &[(&str, &str)] = &[
    ("tau_1", "input"),
    ("tau_2", "input"),
    ("phi_1", "output"),
    ("w_1", "output"),
    ("phi_2", "output"),
    ("w_2", "output"),
    ("dte", "output"),
];
const BODY_CONNECTORS: &[(&str, &str)] = &[("tau", "input"), ("phi", "output"), ("w", "output")];
const SHAFT_CONNECTORS: &[(&str, &str)] = &[
    ("phi_a", "input"),
    ("w_a", "input"),
    ("phi_b", "input"),
    ("w_b", "input"),
    ("tau_a", "output"),
    ("tau_b", "output"),
];

/// The system's connections (from component.connector, to component.connector).
pub const CONNECTIONS: &[(&str, &str, &str, &str)] = &[
    ("motor", "phi", "shaft_1", "phi_a"),
    ("motor", "w", "shaft_1", "w_a"),
    ("gear_pair", "phi_1", "shaft_1", "phi_b"),
    ("gear_pair", "w_1", "shaft_1", "w_b"),
    ("shaft_1", "tau_a", "motor", "tau"),
    ("shaft_1", "tau_b", "gear_pair", "tau_1"),
    ("gear_pair", "phi_2", "shaft_2", "phi_a"),
    ("gear_pair", "w_2", "shaft_2", "w_a"),
    ("load", "phi", "shaft_2", "phi_b"),
    ("load", "w", "shaft_2", "w_b"),
    ("shaft_2", "tau_a", "gear_pair", "tau_2"),
    ("shaft_2", "tau_b", "load", "tau"),
];

fn shaft(name: &'static str, stiffness_nm_per_rad: f64, damping_nms_per_rad: f64) -> Component {
    let element = Element::Shaft { stiffness_nm_per_rad, damping_nms_per_rad };
    Component { name, element: Some(element), connectors: SHAFT_CONNECTORS }
}

/// Writes the SSP archive of the demo drivetrain around the gear FMU `gear_fmu`.
pub fn write_ssp(output: &Path, gear_fmu: &Path, o: &DrivetrainOptions, so: &[u8]) -> Result<()> {
    let gear_bytes = std::fs::read(gear_fmu).with_context(|| format!("cannot read {}", gear_fmu.display()))?;
    let components = [
        Component {
            name: "motor",
            element: Some(Element::Motor {
                inertia_kgm2: o.motor_inertia_kgm2,
                final_torque_nm: o.motor_torque_nm,
                ramp_time_s: o.motor_ramp_s,
                curve: None,
                max_step_s: o.max_step_s,
            }),
            connectors: BODY_CONNECTORS,
        },
        shaft("shaft_1", o.shaft_1_stiffness_nm_per_rad, o.shaft_1_damping_nms_per_rad),
        Component { name: "gear_pair", element: None, connectors: GEAR_CONNECTORS },
        shaft("shaft_2", o.shaft_2_stiffness_nm_per_rad, o.shaft_2_damping_nms_per_rad),
        Component {
            name: "load",
            element: Some(Element::Load {
                inertia_kgm2: o.load_inertia_kgm2,
                viscous_nms_per_rad: o.load_viscous_nms_per_rad,
                quadratic_nms2_per_rad2: 0.0,
                constant_nm: 0.0,
                max_step_s: o.max_step_s,
            }),
            connectors: BODY_CONNECTORS,
        },
    ];
    for c in &components {
        if let Some(e) = &c.element {
            e.check().map_err(|e| anyhow::anyhow!("{}: {e}", c.name))?;
        }
    }
    let out = std::fs::File::create(output).with_context(|| format!("cannot create {}", output.display()))?;
    let mut zip = zip::ZipWriter::new(out);
    let options = zip::write::SimpleFileOptions::default().compression_method(zip::CompressionMethod::Stored);
    for c in &components {
        let bytes = match &c.element {
            None => gear_bytes.clone(),
            Some(e) => element_fmu(c.name, e.clone(), so)?,
        };
        zip.start_file(format!("resources/{}.fmu", c.name), options)?;
        zip.write_all(&bytes)?;
    }
    zip.start_file("SystemStructure.ssd", options)?;
    zip.write_all(system_structure(&components, o).as_bytes())?;
    zip.finish()?;
    println!("wrote {} (motor → shaft_1 → gear_pair → shaft_2 → load)", output.display());
    Ok(())
}

/// SystemStructure.ssd (SSP 1.0): the components with their connectors and, per element, its
/// parameter set inline; the connections; the default experiment.
fn system_structure(components: &[Component], o: &DrivetrainOptions) -> String {
    let mut x = String::new();
    let w = &mut x;
    writeln!(w, r#"<?xml version="1.0" encoding="UTF-8"?>"#).unwrap();
    writeln!(
        w,
        r#"<ssd:SystemStructureDescription xmlns:ssc="http://ssp-standard.org/SSP1/SystemStructureCommon" xmlns:ssd="http://ssp-standard.org/SSP1/SystemStructureDescription" xmlns:ssv="http://ssp-standard.org/SSP1/SystemStructureParameterValues" name="Drivetrain" version="1.0" generationTool="gearfmu fmu-build {}">"#,
        env!("CARGO_PKG_VERSION")
    )
    .unwrap();
    writeln!(
        w,
        r#"  <ssd:System name="Drivetrain" description="motor → shaft_1 → gear_pair → shaft_2 → load; angles, speeds and torques in each gear's mesh sense (the motor in gear 1's, the load in gear 2's); explicit coupling at a communication step of {:?} s">"#,
        o.communication_step_s
    )
    .unwrap();
    writeln!(w, "    <ssd:Elements>").unwrap();
    for c in components {
        writeln!(
            w,
            r#"      <ssd:Component name="{}" source="resources/{}.fmu" type="application/x-fmu-sharedlibrary">"#,
            c.name, c.name
        )
        .unwrap();
        writeln!(w, "        <ssd:Connectors>").unwrap();
        for (name, kind) in c.connectors {
            writeln!(w, r#"          <ssd:Connector name="{name}" kind="{kind}"><ssc:Real/></ssd:Connector>"#).unwrap();
        }
        writeln!(w, "        </ssd:Connectors>").unwrap();
        if let Some(e) = &c.element {
            writeln!(w, "        <ssd:ParameterBindings>").unwrap();
            writeln!(w, "          <ssd:ParameterBinding>").unwrap();
            writeln!(w, "            <ssd:ParameterValues>").unwrap();
            writeln!(w, r#"              <ssv:ParameterSet version="1.0" name="{}">"#, c.name).unwrap();
            writeln!(w, "                <ssv:Parameters>").unwrap();
            for (name, value) in e.parameter_starts() {
                writeln!(
                    w,
                    r#"                  <ssv:Parameter name="{name}"><ssv:Real value="{value:?}"/></ssv:Parameter>"#
                )
                .unwrap();
            }
            writeln!(w, "                </ssv:Parameters>").unwrap();
            writeln!(w, "              </ssv:ParameterSet>").unwrap();
            writeln!(w, "            </ssd:ParameterValues>").unwrap();
            writeln!(w, "          </ssd:ParameterBinding>").unwrap();
            writeln!(w, "        </ssd:ParameterBindings>").unwrap();
        }
        writeln!(w, "      </ssd:Component>").unwrap();
    }
    writeln!(w, "    </ssd:Elements>").unwrap();
    writeln!(w, "    <ssd:Connections>").unwrap();
    for (from, out, to, input) in CONNECTIONS {
        writeln!(
            w,
            r#"      <ssd:Connection startElement="{from}" startConnector="{out}" endElement="{to}" endConnector="{input}"/>"#
        )
        .unwrap();
    }
    writeln!(w, "    </ssd:Connections>").unwrap();
    writeln!(w, "  </ssd:System>").unwrap();
    // SSP 1.0 has no place for the communication step: the system's description and every
    // element FMU's DefaultExperiment carry it (an OSP algorithm annotation made libcosim 0.0.6
    // refuse the file).
    writeln!(w, r#"  <ssd:DefaultExperiment startTime="0" stopTime="{:?}"/>"#, o.stop_time_s).unwrap();
    writeln!(w, "</ssd:SystemStructureDescription>").unwrap();
    x
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every connection joins an output to an input of the components the system has, and every
    /// input is fed exactly once.
    #[test]
    fn every_input_is_fed_once_by_an_output() {
        let connectors = |c: &str| match c {
            "gear_pair" => GEAR_CONNECTORS,
            "shaft_1" | "shaft_2" => SHAFT_CONNECTORS,
            "motor" | "load" => BODY_CONNECTORS,
            other => panic!("unknown component {other}"),
        };
        let kind = |c: &str, n: &str| connectors(c).iter().find(|(name, _)| *name == n).map(|(_, k)| *k);
        for (from, out, to, input) in CONNECTIONS {
            assert_eq!(kind(from, out), Some("output"), "{from}.{out}");
            assert_eq!(kind(to, input), Some("input"), "{to}.{input}");
        }
        for c in ["gear_pair", "shaft_1", "shaft_2", "motor", "load"] {
            for (name, k) in connectors(c) {
                if *k == "input" {
                    let feeds = CONNECTIONS.iter().filter(|(_, _, to, i)| *to == c && i == name).count();
                    assert_eq!(feeds, 1, "{c}.{name}");
                }
            }
        }
    }
}

/// `fmu-build element`: one drivetrain element FMU.
pub(crate) fn element_command(
    kind: ElementKind,
    output: &Path,
    name: Option<String>,
    options: &ElementOptions,
    library: Option<PathBuf>,
) -> Result<()> {
    crate::fmu_archive::check_output_folder(output)?;
    let element = options.element(kind)?;
    let name = name.unwrap_or_else(|| element.kind().to_string());
    let bytes = element_fmu(&name, element, &crate::fmu_archive::library_bytes(library)?)?;
    std::fs::write(output, bytes).with_context(|| format!("cannot create {}", output.display()))?;
    println!("wrote {}", output.display());
    Ok(())
}

/// `fmu-build ssp`: the drivetrain around a gear FMU as an SSP archive.
pub(crate) fn ssp_command(
    gear_fmu: &Path,
    output: &Path,
    options: &DrivetrainOptions,
    library: Option<PathBuf>,
) -> Result<()> {
    crate::fmu_archive::check_output_folder(output)?;
    write_ssp(output, gear_fmu, options, &crate::fmu_archive::library_bytes(library)?)
}
