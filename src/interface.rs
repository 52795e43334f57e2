//! The FMU's variables, read from `modelDescription/variables.toml` (compiled in), the one
//! source of truth for names, value references, causalities, units and start values.

use serde::Deserialize;

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum Start {
    Value(f64),
    /// A Boolean's start value.
    Flag(bool),
    /// "model": taken from the pair's model data when the FMU is built.
    FromModel(String),
}

#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Variable {
    pub name: String,
    pub value_reference: u32,
    #[serde(rename = "type")]
    pub kind: String,
    pub causality: String,
    #[serde(default)]
    pub unit: Option<String>,
    #[serde(default)]
    pub start: Option<Start>,
    pub description: String,
    /// Outputs: the inputs and parameters their value after initialization depends on.
    #[serde(default)]
    pub initial_depends_on: Option<Vec<String>>,
    /// Outputs: the inputs they depend on directly during stepping (none where omitted: the
    /// value reaches the inputs only through a step's integration).
    #[serde(default)]
    pub depends_on: Option<Vec<String>>,
}

#[derive(Deserialize)]
struct File {
    variable: Vec<Variable>,
}

pub const VARIABLES_TOML: &str = include_str!("../modelDescription/variables.toml");

/// All variables, in the order of the file (which is the order of modelDescription.xml). The
/// text is parsed once per process: every instantiation reads this table.
pub fn variables() -> &'static [Variable] {
    static VARIABLES: std::sync::OnceLock<Vec<Variable>> = std::sync::OnceLock::new();
    VARIABLES.get_or_init(|| {
        let file: File =
            toml::from_str(VARIABLES_TOML).expect("modelDescription/variables.toml is valid (checked by tests)");
        file.variable
    })
}

/// The value reference of a variable by name.
pub fn value_reference(name: &str) -> Option<u32> {
    variables().iter().find(|v| v.name == name).map(|v| v.value_reference)
}
