//! The code's digest, `GEARFMU_CODE_DIGEST`: the library's sources, the locked dependencies and
//! the compiler's version, hashed. The build cache (`rom::build_cache`) keys every model by it, so it never hands out a
//! model that other code built.

use std::hash::{DefaultHasher, Hasher};
use std::path::{Path, PathBuf};

fn source_files(dir: &Path, into: &mut Vec<PathBuf>) {
    let mut entries: Vec<PathBuf> =
        std::fs::read_dir(dir).expect("src/ is readable").map(|e| e.expect("a readable entry").path()).collect();
    entries.sort();
    for path in entries {
        if path.is_dir() {
            source_files(&path, into);
        } else {
            into.push(path);
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    source_files(&root.join("src"), &mut files);
    files.extend(["Cargo.toml", "Cargo.lock", "build.rs"].map(|f| root.join(f)));
    // Two 64-bit SipHashes with different prefixes: 128 bits, with no dependency of the build
    // script's own.
    let mut halves = [DefaultHasher::new(), DefaultHasher::new()];
    halves[1].write(b"second half");
    for path in &files {
        let relative = path.strip_prefix(&root).expect("under the manifest directory");
        let bytes = std::fs::read(path).unwrap_or_default(); // no Cargo.lock yet: hashed as empty
        for h in &mut halves {
            h.write(relative.to_string_lossy().as_bytes());
            h.write_usize(bytes.len());
            h.write(&bytes);
        }
    }
    // The compiler too: another rustc may compile the same sources to other floating-point code.
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let version = std::process::Command::new(rustc).arg("-vV").output().map(|o| o.stdout).unwrap_or_default();
    for h in &mut halves {
        h.write(&version);
    }
    println!("cargo:rustc-env=GEARFMU_CODE_DIGEST={:016x}{:016x}", halves[0].finish(), halves[1].finish());
    for watched in ["src", "Cargo.toml", "Cargo.lock", "build.rs"] {
        println!("cargo:rerun-if-changed={watched}");
    }
}
