//! A spec's errors, each naming the field and the rule it broke: shared by the spec and the
//! sections it reads through other modules (flank modifications).

/// Errors of a spec: each names the field and the rule it broke.
#[derive(Debug, thiserror::Error)]
pub enum SpecError {
    /// The OS error is the source, printed once by the caller's error chain, not twice.
    #[error("cannot read spec file {path}")]
    Io { path: String, source: std::io::Error },
    #[error("spec is not valid TOML or has an unknown/missing key: {0}")]
    Parse(String),
    #[error("field `{field}`: {rule}")]
    Invalid { field: String, rule: String },
}

pub(crate) fn invalid(field: &str, rule: impl Into<String>) -> SpecError {
    SpecError::Invalid { field: field.to_string(), rule: rule.into() }
}
