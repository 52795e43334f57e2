//! The rest of a 1-D drivetrain as FMUs (issue 29): a rigid inertia, a torsional shaft, a motor
//! and a load, each behind the same generic FMI layer as the gear pair, so that a master can
//! assemble motor → shaft → gear pair → shaft → load from FMUs alone (an SSP file, no Modelica).
//!
//! Signs are MSL Rotational's, one rule for all (`modelDescription/elements.toml`): an angle and
//! a speed are positive in the body's own sense, a torque input is the torque acting *on* the
//! body, J·ω̇ = Σ τ. The shaft is the massless `SpringDamper` between flanges a and b; its outputs
//! are the torques it exerts on the bodies there, +τ on a and −τ on b with
//! τ = c·(φ_b − φ_a − φ_rel0) + d·(ω_b − ω_a): they depend on its inputs directly (declared so),
//! while every body's outputs reach its inputs only through a step's integration.
//!
//! The bodies (inertia, motor rotor, load) integrate J·ω̇ = τ_in + τ_drive(t, ω) − τ_resist(ω)
//! with the input held over the step, in classical RK4 sub-steps no longer than `max_step`.

use crate::fmi2::{Model, Phase};
use crate::fmu::shared_model::SharedByContent;
use crate::interface::Variable;
use crate::model_file::{ModelFile, ModelKind};
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::sync::Arc;

use super::element_parameters::check_parameter;
pub use super::element_parameters::{variables_of, Element, SpeedTorqueCurve, ELEMENTS_TOML};

/// The bound on RK4 sub-steps per doStep (a few ms of work): a larger request is refused.
pub const MAX_SUBSTEPS: f64 = 1e6;

/// Everything of an element instance that changes: its parameters, its inputs (by value
/// reference 0…3) and, for the bodies, the angle, speed and time since initialization.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ElementState {
    pub element: Element,
    pub inputs: [f64; 4],
    pub start: [f64; 2],
    pub phi: f64,
    pub w: f64,
    pub elapsed_s: f64,
    pub initialized: bool,
}

impl ElementState {
    fn rotor_parameters(&self) -> Option<(f64, f64)> {
        match &self.element {
            Element::Inertia { inertia_kgm2, max_step_s }
            | Element::Motor { inertia_kgm2, max_step_s, .. }
            | Element::Load { inertia_kgm2, max_step_s, .. } => Some((*inertia_kgm2, *max_step_s)),
            Element::Shaft { .. } => None,
        }
    }

    /// The torque acting on the body (N·m) at time t since initialization and speed w: the
    /// inputs, the drive, minus the resistance.
    fn torque_nm(&self, t: f64, w: f64) -> f64 {
        match &self.element {
            Element::Inertia { .. } => self.inputs[0] + self.inputs[1],
            Element::Motor { .. } => self.inputs[0] + self.drive_nm(t, w),
            Element::Load { .. } => self.inputs[0] - self.resistance_nm(w),
            Element::Shaft { .. } => 0.0,
        }
    }

    fn drive_nm(&self, t: f64, w: f64) -> f64 {
        let Element::Motor { final_torque_nm, ramp_time_s, curve, .. } = &self.element else { return 0.0 };
        let ramp = if t >= *ramp_time_s {
            1.0
        } else if t <= 0.0 {
            0.0
        } else {
            (0.5 * std::f64::consts::PI * t / ramp_time_s).sin().powi(2)
        };
        final_torque_nm * ramp * curve.as_ref().map_or(1.0, |c| c.share(w))
    }

    fn resistance_nm(&self, w: f64) -> f64 {
        let Element::Load { viscous_nms_per_rad, quadratic_nms2_per_rad2, constant_nm, .. } = &self.element else {
            return 0.0;
        };
        viscous_nms_per_rad * w + quadratic_nms2_per_rad2 * w * w.abs() + constant_nm
    }

    /// The shaft's torque on the body at flange a.
    fn shaft_torque_nm(&self) -> f64 {
        let Element::Shaft { stiffness_nm_per_rad, damping_nms_per_rad } = &self.element else { return 0.0 };
        let [phi_a, w_a, phi_b, w_b] = self.inputs;
        stiffness_nm_per_rad * (phi_b - phi_a - self.start[0]) + damping_nms_per_rad * (w_b - w_a)
    }

    /// Classical RK4 on (φ, ω) over h in equal sub-steps no longer than max_step.
    fn advance(&mut self, h: f64) {
        let Some((inertia, max_step)) = self.rotor_parameters() else { return };
        let n = crate::dynamics::substep_count(h, max_step);
        let dt = h / n as f64;
        let accel = |s: &Self, t: f64, w: f64| s.torque_nm(t, w) / inertia;
        for k in 0..n {
            let t = self.elapsed_s + k as f64 * dt;
            let (phi, w) = (self.phi, self.w);
            let (k1p, k1w) = (w, accel(self, t, w));
            let (k2p, k2w) = (w + 0.5 * dt * k1w, accel(self, t + 0.5 * dt, w + 0.5 * dt * k1w));
            let (k3p, k3w) = (w + 0.5 * dt * k2w, accel(self, t + 0.5 * dt, w + 0.5 * dt * k2w));
            let (k4p, k4w) = (w + dt * k3w, accel(self, t + dt, w + dt * k3w));
            self.phi = phi + dt / 6.0 * (k1p + 2.0 * k2p + 2.0 * k3p + k4p);
            self.w = w + dt / 6.0 * (k1w + 2.0 * k2w + 2.0 * k3w + k4w);
        }
        self.elapsed_s += h;
    }
}

/// An element FMU: its build-time data, shared by the instances of one file.
#[derive(Debug)]
pub struct LoadedElement {
    pub guid: String,
    pub element: Element,
}

#[derive(Debug, Clone)]
pub struct ElementFmu(pub Arc<LoadedElement>);

impl LoadedElement {
    pub fn from_model_file(file: ModelFile) -> Result<Self, String> {
        match file.model {
            ModelKind::Element(element) => {
                element.check()?;
                Ok(LoadedElement { guid: file.guid, element })
            }
            _ => Err("the model file holds a gear pair, not a drivetrain element".into()),
        }
    }
}

impl ElementFmu {
    /// The element of a model file's bytes, shared with the live instances of the same bytes.
    pub fn from_bytes(bytes: Vec<u8>, guid: &str) -> Result<Self, String> {
        static LOADED: SharedByContent<LoadedElement> = SharedByContent::new();
        let loaded =
            LOADED.get_or_load(bytes, |bytes| LoadedElement::from_model_file(ModelFile::from_bytes(bytes)?))?;
        crate::fmu::gear_pair::check_guid(&loaded.guid, guid)?;
        Ok(ElementFmu(loaded))
    }

    fn variable(&self, vr: u32) -> Result<&'static Variable, String> {
        let element = &self.0.element;
        element
            .variables()
            .iter()
            .find(|v| v.value_reference == vr)
            .ok_or_else(|| format!("value reference {vr} is not a variable of this {} FMU", element.kind()))
    }
}

/// The parameter `name` of an element, as a mutable reference (None: not a parameter of it).
fn parameter_mut<'a>(s: &'a mut ElementState, name: &str) -> Option<&'a mut f64> {
    Some(match (&mut s.element, name) {
        (_, "phi_start") => &mut s.start[0],
        (_, "phi_rel0") => &mut s.start[0],
        (_, "w_start") => &mut s.start[1],
        (Element::Inertia { inertia_kgm2, .. }, "J")
        | (Element::Motor { inertia_kgm2, .. }, "J")
        | (Element::Load { inertia_kgm2, .. }, "J") => inertia_kgm2,
        (Element::Inertia { max_step_s, .. }, "max_step")
        | (Element::Motor { max_step_s, .. }, "max_step")
        | (Element::Load { max_step_s, .. }, "max_step") => max_step_s,
        (Element::Shaft { stiffness_nm_per_rad, .. }, "c") => stiffness_nm_per_rad,
        (Element::Shaft { damping_nms_per_rad, .. }, "d") => damping_nms_per_rad,
        (Element::Motor { final_torque_nm, .. }, "tau_final") => final_torque_nm,
        (Element::Motor { ramp_time_s, .. }, "t_ramp") => ramp_time_s,
        (Element::Load { viscous_nms_per_rad, .. }, "viscous") => viscous_nms_per_rad,
        (Element::Load { quadratic_nms2_per_rad2, .. }, "quadratic") => quadratic_nms2_per_rad2,
        (Element::Load { constant_nm, .. }, "constant") => constant_nm,
        _ => return None,
    })
}

impl Model for ElementFmu {
    type State = ElementState;

    fn load(resources: &Path, guid: &str) -> Result<Self, String> {
        ElementFmu::from_bytes(ModelFile::read_bytes(resources)?, guid)
    }

    fn initial_state(&self) -> ElementState {
        ElementState {
            element: self.0.element.clone(),
            inputs: [0.0; 4],
            start: [0.0; 2],
            phi: 0.0,
            w: 0.0,
            elapsed_s: 0.0,
            initialized: false,
        }
    }

    fn set_real(&self, s: &mut ElementState, vr: u32, value: f64, phase: Phase) -> Result<(), String> {
        let v = self.variable(vr)?;
        match v.causality.as_str() {
            "input" => {
                s.inputs[vr as usize] = value;
                Ok(())
            }
            "parameter" if matches!(phase, Phase::Instantiated | Phase::InitializationMode) => {
                check_parameter(s.element.kind(), &v.name, value)?;
                *parameter_mut(s, &v.name).ok_or_else(|| format!("{} has no physics behind it", v.name))? = value;
                (s.phi, s.w) = (s.start[0], s.start[1]);
                Ok(())
            }
            "parameter" => {
                Err(format!("{} is a fixed parameter: it can be set only before initialization ends", v.name))
            }
            _ => Err(format!("{} is an output and cannot be set", v.name)),
        }
    }

    fn get_real(&self, s: &ElementState, vr: u32) -> Result<f64, String> {
        let v = self.variable(vr)?;
        if v.causality == "input" {
            return Ok(s.inputs[vr as usize]);
        }
        if v.causality == "parameter" {
            // The start values live in the state, the others in its element (as the build's).
            let value = match v.name.as_str() {
                "phi_start" | "phi_rel0" => Some(s.start[0]),
                "w_start" => Some(s.start[1]),
                name => s.element.parameter_starts().into_iter().find(|(n, _)| *n == name).map(|(_, x)| x),
            };
            return value.ok_or_else(|| format!("{} has no physics behind it", v.name));
        }
        Ok(match v.name.as_str() {
            "phi" => s.phi,
            "w" => s.w,
            "tau_drive" => s.drive_nm(s.elapsed_s, s.w),
            "tau_load" => s.resistance_nm(s.w),
            "tau_a" => s.shaft_torque_nm(),
            "tau_b" => -s.shaft_torque_nm(),
            other => return Err(format!("{other} has no physics behind it")),
        })
    }

    fn get_integer(&self, _s: &ElementState, vr: u32) -> Result<i32, String> {
        Err(format!("value reference {vr} is not an Integer of this {} FMU", self.0.element.kind()))
    }

    fn get_boolean(&self, _s: &ElementState, vr: u32) -> Result<bool, String> {
        Err(format!("value reference {vr} is not a Boolean of this {} FMU", self.0.element.kind()))
    }

    fn set_boolean(&self, _s: &mut ElementState, vr: u32, _value: bool, _phase: Phase) -> Result<(), String> {
        Err(format!("value reference {vr} is not a Boolean of this {} FMU", self.0.element.kind()))
    }

    fn exit_initialization(&self, s: &mut ElementState) -> Result<(), String> {
        s.element.check()?;
        (s.phi, s.w, s.elapsed_s, s.initialized) = (s.start[0], s.start[1], 0.0, true);
        Ok(())
    }

    fn check_step(&self, s: &ElementState, h: f64) -> Result<(), String> {
        let Some((_, max_step)) = s.rotor_parameters() else { return Ok(()) };
        crate::dynamics::check_substep_bound(h, max_step, MAX_SUBSTEPS)
    }

    fn check_state(&self, s: &ElementState, initialized: bool) -> Result<(), String> {
        if s.element.kind() != self.0.element.kind() {
            return Err(format!(
                "a {} state cannot be restored into a {} FMU",
                s.element.kind(),
                self.0.element.kind()
            ));
        }
        s.element.check()?;
        if let (Element::Motor { curve: a, .. }, Element::Motor { curve: b, .. }) = (&s.element, &self.0.element) {
            if a != b {
                return Err("the state's speed–torque curve is not this motor's".into());
            }
        }
        let values =
            [s.inputs[0], s.inputs[1], s.inputs[2], s.inputs[3], s.start[0], s.start[1], s.phi, s.w, s.elapsed_s];
        if let Some(x) = values.iter().find(|x| !x.is_finite()) {
            return Err(format!("the state holds a non-finite value {x}"));
        }
        if initialized && !s.initialized {
            return Err("the state was taken before initialization ended".into());
        }
        Ok(())
    }

    fn do_step(&self, s: &mut ElementState, h: f64) -> Result<(), String> {
        self.check_step(s, h)?;
        let mut next = s.clone();
        next.advance(h);
        if !(next.phi.is_finite() && next.w.is_finite()) {
            return Err(format!(
                "the {} state became non-finite over a step of {h:e} s (max_step {:e} s too long for its torques?)",
                s.element.kind(),
                s.rotor_parameters().map_or(0.0, |p| p.1)
            ));
        }
        *s = next;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inertia(j: f64) -> ElementState {
        let loaded = ElementFmu(Arc::new(LoadedElement {
            guid: String::new(),
            element: Element::Inertia { inertia_kgm2: j, max_step_s: 1e-3 },
        }));
        loaded.initial_state()
    }

    /// Closed form: a constant torque τ on J from rest gives ω = τt/J, φ = τt²/(2J); RK4 is exact
    /// on this polynomial motion to round-off.
    #[test]
    fn a_constant_torque_accelerates_an_inertia_as_the_closed_form() {
        let mut s = inertia(0.5);
        s.inputs = [3.0, -1.0, 0.0, 0.0];
        s.advance(0.37);
        let (tau, t, j) = (2.0, 0.37, 0.5);
        assert!((s.w - tau * t / j).abs() < 1e-12, "{}", s.w);
        assert!((s.phi - tau * t * t / (2.0 * j)).abs() < 1e-12, "{}", s.phi);
    }

    /// Closed form: a viscous load coasting from ω₀ decays as ω₀·e^(−ct/J); classical RK4's
    /// amplification 1 + z + … + z⁴/24 exceeds e^z by −z⁵/120 per step (z = −c·h/J), so after N
    /// steps the relative error is N·(−z)⁵/120 to leading order: checked to 1 %.
    #[test]
    fn a_viscous_load_coasts_down_exponentially() {
        let element = Element::Load {
            inertia_kgm2: 0.2,
            viscous_nms_per_rad: 2.0,
            quadratic_nms2_per_rad2: 0.0,
            constant_nm: 0.0,
            max_step_s: 1e-3,
        };
        let fmu = ElementFmu(Arc::new(LoadedElement { guid: String::new(), element }));
        let mut s = fmu.initial_state();
        s.w = 50.0;
        s.advance(0.3);
        let exact = 50.0 * (-2.0 * 0.3 / 0.2f64).exp();
        let z: f64 = -2.0 * 1e-3 / 0.2;
        let predicted = 300.0 * (-z).powi(5) / 120.0;
        assert!(((s.w / exact - 1.0) / predicted - 1.0).abs() < 0.01, "{} vs {exact}", s.w);
    }

    /// Closed forms of the drive and the resistance: the haversine ramp at half its time is half
    /// the torque; a speed–torque curve scales it by curve(ω)/peak, linear between its points
    /// and held beyond them; the load's torque is c·ω + a·ω|ω| + T₀ at either sign of ω.
    #[test]
    fn drive_and_resistance_follow_their_closed_forms() {
        let curve = SpeedTorqueCurve::new(vec![0.0, 100.0, 200.0], vec![300.0, 300.0, 0.0]).unwrap();
        let motor = |curve| Element::Motor {
            inertia_kgm2: 1.0,
            final_torque_nm: 150.0,
            ramp_time_s: 0.02,
            curve,
            max_step_s: 1e-4,
        };
        let state = |element| ElementFmu(Arc::new(LoadedElement { guid: String::new(), element })).initial_state();
        let ramp = state(motor(None));
        assert!((ramp.drive_nm(0.01, 0.0) - 75.0).abs() < 1e-12);
        assert_eq!(ramp.drive_nm(0.05, 0.0), 150.0);
        assert_eq!(ramp.drive_nm(-1.0, 0.0), 0.0);
        let curved = state(motor(Some(curve)));
        assert!((curved.drive_nm(1.0, 150.0) - 75.0).abs() < 1e-12, "half the peak at 150 rad/s");
        assert_eq!(curved.drive_nm(1.0, 250.0), 0.0, "held beyond the last point");
        assert_eq!(curved.drive_nm(1.0, -5.0), 150.0, "held below the first point");
        let load = state(Element::Load {
            inertia_kgm2: 1.0,
            viscous_nms_per_rad: 2.0,
            quadratic_nms2_per_rad2: 0.01,
            constant_nm: 5.0,
            max_step_s: 1e-4,
        });
        assert!((load.resistance_nm(10.0) - (20.0 + 1.0 + 5.0)).abs() < 1e-12);
        assert!((load.resistance_nm(-10.0) - (-20.0 - 1.0 + 5.0)).abs() < 1e-12);
        assert!(SpeedTorqueCurve::new(vec![0.0, 0.0], vec![1.0, 2.0]).unwrap_err().contains("ascend strictly"));
    }

    #[test]
    fn the_element_tables_parse_and_every_parameter_has_physics() {
        let elements = [
            Element::Inertia { inertia_kgm2: 1.0, max_step_s: 1e-4 },
            Element::Shaft { stiffness_nm_per_rad: 1.0, damping_nms_per_rad: 0.0 },
            Element::Motor { inertia_kgm2: 1.0, final_torque_nm: 1.0, ramp_time_s: 0.1, curve: None, max_step_s: 1e-4 },
            Element::Load {
                inertia_kgm2: 1.0,
                viscous_nms_per_rad: 1.0,
                quadratic_nms2_per_rad2: 0.0,
                constant_nm: 0.0,
                max_step_s: 1e-4,
            },
        ];
        for element in elements {
            let fmu = ElementFmu(Arc::new(LoadedElement { guid: String::new(), element }));
            let mut s = fmu.initial_state();
            for v in fmu.0.element.variables() {
                assert!(v.value_reference < 4 || v.causality != "input", "{}: inputs are 0…3", v.name);
                let value = fmu.get_real(&s, v.value_reference).unwrap();
                if v.causality == "parameter" {
                    fmu.set_real(&mut s, v.value_reference, value, Phase::Instantiated).unwrap();
                }
            }
        }
    }
}
