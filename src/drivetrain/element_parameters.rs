//! The drivetrain elements' kinds and parameters (issue 29): plain data, what an element FMU's
//! model file carries (`model_file::ModelKind::Element`), checked against the rules of
//! `modelDescription/elements.toml`, whose variables it also reads. The elements' physics and
//! FMU glue are in `drivetrain::elements`.

use crate::interface::Variable;
use serde::{Deserialize, Serialize};

pub const ELEMENTS_TOML: &str = include_str!("../../modelDescription/elements.toml");

/// A motor's speed–torque curve: torque (N·m) at ascending speeds (rad/s), linear between the
/// points and held beyond the ends.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SpeedTorqueCurve {
    pub speed_rad_s: Vec<f64>,
    pub torque_nm: Vec<f64>,
}

impl SpeedTorqueCurve {
    /// The curve, or why not: at least two points, speeds strictly ascending, all finite.
    pub fn new(speed_rad_s: Vec<f64>, torque_nm: Vec<f64>) -> Result<Self, String> {
        if speed_rad_s.len() < 2 || speed_rad_s.len() != torque_nm.len() {
            return Err(format!(
                "a speed–torque curve needs at least two (speed, torque) points of equal count, got {} speeds and {} torques",
                speed_rad_s.len(),
                torque_nm.len()
            ));
        }
        if speed_rad_s.iter().chain(&torque_nm).any(|x| !x.is_finite()) {
            return Err("a speed–torque curve's points must be finite".into());
        }
        if speed_rad_s.windows(2).any(|w| w[1] <= w[0]) {
            return Err("a speed–torque curve's speeds must ascend strictly".into());
        }
        if torque_nm.iter().all(|&t| t == 0.0) {
            return Err("a speed–torque curve must have a nonzero torque somewhere".into());
        }
        Ok(SpeedTorqueCurve { speed_rad_s, torque_nm })
    }

    /// The curve's torque at speed w, as a share of its largest |torque|.
    pub(crate) fn share(&self, w: f64) -> f64 {
        let (s, t) = (&self.speed_rad_s, &self.torque_nm);
        let peak = t.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        let torque = if w <= s[0] {
            t[0]
        } else if w >= s[s.len() - 1] {
            t[t.len() - 1]
        } else {
            let i = s.partition_point(|&x| x <= w) - 1;
            t[i] + (t[i + 1] - t[i]) * (w - s[i]) / (s[i + 1] - s[i])
        };
        torque / peak
    }
}

/// One element's physics and its parameters (the build's values; an instance may set its own
/// before initialization ends).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum Element {
    /// A rigid body with a torque at each of its two flanges.
    Inertia { inertia_kgm2: f64, max_step_s: f64 },
    /// A massless spring–damper between two flanges.
    Shaft { stiffness_nm_per_rad: f64, damping_nms_per_rad: f64 },
    /// A rotor driven by τ_final·ramp(t)·(curve(ω) / its peak, or 1 without a curve), the ramp
    /// sin²(π/2·t/t_ramp) up to t_ramp and 1 after (t from the end of initialization).
    Motor {
        inertia_kgm2: f64,
        final_torque_nm: f64,
        ramp_time_s: f64,
        curve: Option<SpeedTorqueCurve>,
        max_step_s: f64,
    },
    /// A rotor braked by viscous·ω + quadratic·ω|ω| + constant.
    Load {
        inertia_kgm2: f64,
        viscous_nms_per_rad: f64,
        quadratic_nms2_per_rad2: f64,
        constant_nm: f64,
        max_step_s: f64,
    },
}

impl Element {
    /// The kind's name: its table in elements.toml.
    pub fn kind(&self) -> &'static str {
        match self {
            Element::Inertia { .. } => "inertia",
            Element::Shaft { .. } => "shaft",
            Element::Motor { .. } => "motor",
            Element::Load { .. } => "load",
        }
    }

    /// The kind's variables (elements.toml).
    pub fn variables(&self) -> &'static [Variable] {
        variables_of(self.kind())
    }

    /// The build's parameter values by variable name (modelDescription's start values).
    pub fn parameter_starts(&self) -> Vec<(&'static str, f64)> {
        match self {
            Element::Inertia { inertia_kgm2, max_step_s } => vec![("J", *inertia_kgm2), ("max_step", *max_step_s)],
            Element::Shaft { stiffness_nm_per_rad, damping_nms_per_rad } => {
                vec![("c", *stiffness_nm_per_rad), ("d", *damping_nms_per_rad)]
            }
            Element::Motor { inertia_kgm2, final_torque_nm, ramp_time_s, max_step_s, .. } => vec![
                ("J", *inertia_kgm2),
                ("tau_final", *final_torque_nm),
                ("t_ramp", *ramp_time_s),
                ("max_step", *max_step_s),
            ],
            Element::Load { inertia_kgm2, viscous_nms_per_rad, quadratic_nms2_per_rad2, constant_nm, max_step_s } => {
                vec![
                    ("J", *inertia_kgm2),
                    ("viscous", *viscous_nms_per_rad),
                    ("quadratic", *quadratic_nms2_per_rad2),
                    ("constant", *constant_nm),
                    ("max_step", *max_step_s),
                ]
            }
        }
    }

    /// Checks every parameter; the message names the variable and the rule.
    pub fn check(&self) -> Result<(), String> {
        for (name, value) in self.parameter_starts() {
            check_parameter(self.kind(), name, value)?;
        }
        Ok(())
    }
}

/// The rule of each parameter (by the variable's name).
pub(crate) fn check_parameter(kind: &str, name: &str, value: f64) -> Result<(), String> {
    let (ok, rule) = match name {
        "J" | "max_step" => (value.is_finite() && value > 0.0 && value.is_normal(), "a finite number > 0"),
        "c" | "d" | "viscous" | "quadratic" | "t_ramp" => (value.is_finite() && value >= 0.0, "a finite number ≥ 0"),
        _ => (value.is_finite(), "finite"),
    };
    if ok {
        Ok(())
    } else {
        Err(format!("{kind} parameter {name} must be {rule}, got {value:e}"))
    }
}

#[derive(Deserialize)]
struct Tables {
    inertia: Vec<Variable>,
    shaft: Vec<Variable>,
    motor: Vec<Variable>,
    load: Vec<Variable>,
}

fn tables() -> &'static Tables {
    static TABLES: std::sync::OnceLock<Tables> = std::sync::OnceLock::new();
    TABLES.get_or_init(|| {
        toml::from_str(ELEMENTS_TOML).expect("modelDescription/elements.toml is valid (checked by tests)")
    })
}

/// The variables of an element kind ("inertia", "shaft", "motor", "load").
pub fn variables_of(kind: &str) -> &'static [Variable] {
    let t = tables();
    match kind {
        "inertia" => &t.inertia,
        "shaft" => &t.shaft,
        "motor" => &t.motor,
        "load" => &t.load,
        other => panic!("no element kind {other}"),
    }
}
