//! One FMU binary for every model the tool builds: the gear pair (lumped or PMOR-Hertz) and the
//! drivetrain elements. The model file's kind picks the model at instantiation; each keeps its
//! own interface and state, and this file only forwards.

use super::gear_pair::{GearPairFmu, GearPairState};
use crate::drivetrain::elements::{ElementFmu, ElementState};
use crate::fmi2::{Model, Phase};
use crate::model_file::ModelFile;
use serde::{Deserialize, Serialize};
use std::path::Path;

pub enum AnyModel {
    GearPair(GearPairFmu),
    Element(ElementFmu),
}

/// The state of whichever model an FMU carries (an FMU state is a copy of it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum AnyState {
    GearPair(Box<GearPairState>),
    Element(ElementState),
}

impl AnyState {
    /// The gear pair's state, where this is one.
    pub fn gear_pair(&self) -> Option<&GearPairState> {
        match self {
            AnyState::GearPair(s) => Some(s),
            AnyState::Element(_) => None,
        }
    }

    pub fn gear_pair_mut(&mut self) -> Option<&mut GearPairState> {
        match self {
            AnyState::GearPair(s) => Some(s),
            AnyState::Element(_) => None,
        }
    }

    pub fn into_gear_pair(self) -> Option<GearPairState> {
        match self {
            AnyState::GearPair(s) => Some(*s),
            AnyState::Element(_) => None,
        }
    }
}

impl From<GearPairState> for AnyState {
    fn from(s: GearPairState) -> Self {
        AnyState::GearPair(Box::new(s))
    }
}

const MISMATCH: &str = "the state belongs to another kind of model than this FMU's";

/// Forwards one call to the model the FMU carries, with the state of the same kind.
macro_rules! forward {
    ($self:expr, $state:expr, $m:ident, $s:ident => $call:expr) => {
        match ($self, $state) {
            (AnyModel::GearPair($m), AnyState::GearPair($s)) => $call,
            (AnyModel::Element($m), AnyState::Element($s)) => $call,
            _ => Err(MISMATCH.to_string()),
        }
    };
}

impl Model for AnyModel {
    type State = AnyState;

    fn load(resources: &Path, guid: &str) -> Result<Self, String> {
        let bytes = ModelFile::read_bytes(resources)?;
        if ModelFile::holds_gear_pair(&bytes)? {
            Ok(AnyModel::GearPair(GearPairFmu::from_bytes(bytes, guid)?))
        } else {
            Ok(AnyModel::Element(ElementFmu::from_bytes(bytes, guid)?))
        }
    }

    fn initial_state(&self) -> AnyState {
        match self {
            AnyModel::GearPair(m) => AnyState::GearPair(Box::new(m.initial_state())),
            AnyModel::Element(m) => AnyState::Element(m.initial_state()),
        }
    }

    fn set_real(&self, state: &mut AnyState, vr: u32, value: f64, phase: Phase) -> Result<(), String> {
        forward!(self, state, m, s => m.set_real(s, vr, value, phase))
    }

    fn get_real(&self, state: &AnyState, vr: u32) -> Result<f64, String> {
        forward!(self, state, m, s => m.get_real(s, vr))
    }

    fn get_integer(&self, state: &AnyState, vr: u32) -> Result<i32, String> {
        forward!(self, state, m, s => m.get_integer(s, vr))
    }

    fn get_boolean(&self, state: &AnyState, vr: u32) -> Result<bool, String> {
        forward!(self, state, m, s => m.get_boolean(s, vr))
    }

    fn set_boolean(&self, state: &mut AnyState, vr: u32, value: bool, phase: Phase) -> Result<(), String> {
        forward!(self, state, m, s => m.set_boolean(s, vr, value, phase))
    }

    fn exit_initialization(&self, state: &mut AnyState) -> Result<(), String> {
        forward!(self, state, m, s => m.exit_initialization(s))
    }

    fn check_step(&self, state: &AnyState, h: f64) -> Result<(), String> {
        forward!(self, state, m, s => m.check_step(s, h))
    }

    fn check_state(&self, state: &AnyState, initialized: bool) -> Result<(), String> {
        forward!(self, state, m, s => m.check_state(s, initialized))
    }

    fn do_step(&self, state: &mut AnyState, h: f64) -> Result<(), String> {
        forward!(self, state, m, s => m.do_step(s, h))
    }

    fn take_warnings(&self, state: &mut AnyState) -> Vec<String> {
        match (self, state) {
            (AnyModel::GearPair(m), AnyState::GearPair(s)) => m.take_warnings(s),
            (AnyModel::Element(m), AnyState::Element(s)) => m.take_warnings(s),
            _ => Vec::new(),
        }
    }
}
