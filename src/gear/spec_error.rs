//! A spec's errors, each naming the field and the rule it broke, and how a message prints a
//! number (`sig`): shared by the spec and the sections it reads through other modules (flank
//! modifications, lubrication).

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

/// A number with six significant digits, in exponent form when it is very large or small: what
/// a message prints of a value a user typed (1e200 is not worth 200 digits).
pub fn sig(value: f64) -> String {
    let a = value.abs();
    if value == 0.0 || !value.is_finite() {
        return format!("{value}");
    }
    if !(1e-4..1e7).contains(&a) {
        return format!("{value:.5e}");
    }
    let decimals = (5 - a.log10().floor() as i32).max(0) as usize;
    let text = format!("{value:.decimals$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}
