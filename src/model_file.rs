//! The model data file that crosses from offline (fmu-build) to online (the FMU):
//! `resources/model.bin`. Layout: 8-byte magic, u32 format version (LE), 32-byte SHA-256 of the
//! body, then the body in postcard. A wrong magic, version or checksum is refused with a message
//! that says which, so a stale or damaged FMU fails at instantiate, never later.

use crate::drivetrain::element_parameters::Element;
use crate::dynamics::lumped::LumpedMesh;
use crate::dynamics::pmor::model::PmorModel;
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::path::Path;

pub const MAGIC: &[u8; 8] = b"GEARFMU\0";
pub const FORMAT_VERSION: u32 = 17;
pub const FILE_NAME: &str = "model.bin";

/// `ModelKind::Element`'s place among the variants (postcard's variant index).
const ELEMENT_VARIANT: u32 = 2;

/// Which fidelity level the FMU carries.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum ModelKind {
    /// Rigid gears on a potential-energy mesh law (`dynamics::lumped`).
    Lumped(LumpedMesh),
    /// The FE-based reduced pair in floating frames (`dynamics::pmor`).
    PmorHertz(Box<PmorModel>),
    /// A drivetrain element: inertia, shaft, motor or load (`drivetrain::elements`).
    Element(Element),
}

impl ModelKind {
    /// Whether this kind is a gear pair (the gear FMU's interface) or an element (its own).
    pub fn is_gear_pair(&self) -> bool {
        !matches!(self, ModelKind::Element(_))
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ModelFile {
    /// The FMU's GUID (a hash of the interface and the model data): instantiate checks it.
    pub guid: String,
    pub pair_name: String,
    pub model: ModelKind,
}

impl ModelFile {
    pub fn to_bytes(&self) -> Vec<u8> {
        let body = postcard::to_allocvec(self).expect("model data serializes");
        let mut bytes = Vec::with_capacity(44 + body.len());
        bytes.extend_from_slice(MAGIC);
        bytes.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
        bytes.extend_from_slice(&Sha256::digest(&body));
        bytes.extend_from_slice(&body);
        bytes
    }

    pub fn from_bytes(bytes: &[u8]) -> Result<ModelFile, String> {
        if bytes.len() < 44 || &bytes[..8] != MAGIC {
            return Err("model data file is not a gearfmu model file (bad magic)".into());
        }
        let version = u32::from_le_bytes(bytes[8..12].try_into().unwrap());
        if version != FORMAT_VERSION {
            return Err(format!(
                "model data file has format version {version}, this FMU binary reads version {FORMAT_VERSION}; rebuild the FMU"
            ));
        }
        let (checksum, body) = bytes[12..].split_at(32);
        if Sha256::digest(body).as_slice() != checksum {
            return Err("model data file is corrupted (checksum mismatch)".into());
        }
        postcard::from_bytes(body).map_err(|e| format!("model data file cannot be decoded: {e}"))
    }

    /// Whether the file's model is a gear pair, read from the body's first fields only (no
    /// checksum, no decoding of the model): which loader to hand the file to. The loader then
    /// checks the whole file.
    pub fn holds_gear_pair(bytes: &[u8]) -> Result<bool, String> {
        if bytes.len() < 44 || &bytes[..8] != MAGIC {
            return Err("model data file is not a gearfmu model file (bad magic)".into());
        }
        // postcard writes the fields in order and an enum's variant as a varint u32.
        let (prefix, _): ((String, String, u32), _) =
            postcard::take_from_bytes(&bytes[44..]).map_err(|e| format!("model data file cannot be decoded: {e}"))?;
        Ok(prefix.2 != ELEMENT_VARIANT)
    }

    pub fn read(resources: &Path) -> Result<ModelFile, String> {
        Self::from_bytes(&Self::read_bytes(resources)?)
    }

    /// The model file's bytes, from an FMU's resources folder.
    pub fn read_bytes(resources: &Path) -> Result<Vec<u8>, String> {
        let path = resources.join(FILE_NAME);
        std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))
    }

    /// GUID = SHA-256 of the interface text and the model body, formatted as a UUID-like string.
    pub fn compute_guid(interface_toml: &str, pair_name: &str, model: &ModelKind) -> String {
        let mut h = Sha256::new();
        h.update(interface_toml.as_bytes());
        h.update(pair_name.as_bytes());
        h.update(postcard::to_allocvec(model).expect("model data serializes"));
        let d = h.finalize();
        let hex: String = d.iter().take(16).map(|b| format!("{b:02x}")).collect();
        format!("{{{}-{}-{}-{}-{}}}", &hex[0..8], &hex[8..12], &hex[12..16], &hex[16..20], &hex[20..32])
    }
}
