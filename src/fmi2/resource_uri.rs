//! The `fmuResourceLocation` URI → a local path. FMI 2.0 passes a URI (RFC 3986) to the
//! resources folder; masters write `file:///abs/path`, `file:/abs/path` or `file://localhost/…`,
//! percent-encoded.

use std::path::PathBuf;

pub fn resource_path(uri: &str) -> Result<PathBuf, String> {
    let rest = uri
        .strip_prefix("file://localhost/")
        .map(|r| format!("/{r}"))
        .or_else(|| uri.strip_prefix("file:///").map(|r| format!("/{r}")))
        .or_else(|| uri.strip_prefix("file:/").filter(|r| !r.starts_with('/')).map(|r| format!("/{r}")))
        .ok_or_else(|| format!("fmuResourceLocation must be a local file URI (file:///… or file:/…), got \"{uri}\""))?;
    let decoded = percent_encoding::percent_decode_str(&rest)
        .decode_utf8()
        .map_err(|e| format!("fmuResourceLocation \"{uri}\" is not valid UTF-8 after percent-decoding: {e}"))?;
    Ok(PathBuf::from(decoded.as_ref()))
}

#[cfg(test)]
mod tests {
    use super::*;
    #[test]
    fn accepts_the_forms_masters_write() {
        let expect = PathBuf::from("/tmp/a b/resources");
        assert_eq!(resource_path("file:///tmp/a%20b/resources").unwrap(), expect);
        assert_eq!(resource_path("file:/tmp/a%20b/resources").unwrap(), expect);
        assert_eq!(resource_path("file://localhost/tmp/a%20b/resources").unwrap(), expect);
        assert!(resource_path("http://example.org/resources").is_err());
        assert!(resource_path("/tmp/resources").is_err());
    }
}
