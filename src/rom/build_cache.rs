//! A directory of built models: one FE reduction per distinct model, shared by every process
//! that builds one — the Rust tests, `fmu-build` and the Python tests that call it (issue 41).
//!
//! An entry is keyed by everything that decides the model: the code (`GEARFMU_CODE_DIGEST`, the
//! library's sources, locked dependencies and the compiler, from `build.rs`), the build profile,
//! the pair, the mesh and the build options. A hit is therefore the model this code builds on
//! this machine, bit for bit (`the_build_cache_returns_what_the_build_makes` in `pmor_dynamics`),
//! and the report of the build that stored it: its memory estimate and schedule are that
//! build's (they depend on the threads and the memory available then, and decide only the order
//! of the work, not the model: `tests/build_memory.rs`, `a_build_that_does_not_fit_runs_the_gears_one_after_the_other_or_is_refused_with_the_figure`),
//! so the memory limit is no part of the key and a hit is not refused for memory. The cache is
//! off unless asked for: `GEARFMU_BUILD_CACHE=<directory>`.

use super::dynamic_reductor::{build_dynamic_model, DynamicBuildOptions, DynamicBuildReport};
use crate::dynamics::pmor::model::PmorModel;
use crate::fe::gear_mesh::MeshSpec;
use crate::gear::GearPair;
use sha2::{Digest, Sha256};
use std::path::{Path, PathBuf};

/// The environment variable naming the cache's directory.
pub const BUILD_CACHE_ENV: &str = "GEARFMU_BUILD_CACHE";

/// The library's sources and locked dependencies, hashed at compile time (`build.rs`).
pub const CODE_DIGEST: &str = env!("GEARFMU_CODE_DIGEST");

/// The directory of built models.
pub struct BuildCache {
    dir: PathBuf,
}

impl BuildCache {
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        BuildCache { dir: dir.into() }
    }

    /// The cache `GEARFMU_BUILD_CACHE` names, if it is set and not empty.
    pub fn from_env() -> Option<Self> {
        std::env::var_os(BUILD_CACHE_ENV).filter(|d| !d.is_empty()).map(BuildCache::new)
    }

    /// The entry of a model. Debug formatting is exact for every field (an `f64` prints the
    /// shortest text that reads back to the same bits), so two builds that differ in any input
    /// have different keys.
    pub fn entry(&self, pair: &GearPair, mesh: &MeshSpec, options: &DynamicBuildOptions) -> PathBuf {
        // The memory limit decides the schedule, not the model (module doc).
        let options = DynamicBuildOptions { memory_limit_bytes: None, ..options.clone() };
        let mut key = Sha256::new();
        key.update(CODE_DIGEST.as_bytes());
        key.update(if cfg!(debug_assertions) { b"\0debug" } else { b"\0optim" });
        key.update(format!("\0{pair:?}\0{mesh:?}\0{options:?}").as_bytes());
        let hex: String = key.finalize().iter().take(16).map(|b| format!("{b:02x}")).collect();
        self.dir.join(format!("{}{hex}.postcard", Self::code_prefix()))
    }

    /// Every entry's name starts with the code's digest: entries of other code are never hit, and
    /// `store` removes them, so the cache holds one version of the code's models.
    fn code_prefix() -> String {
        format!("pmor-{}-", &CODE_DIGEST[..16])
    }

    /// `build_dynamic_model`, or the model stored by an earlier build of the same entry. A
    /// stored entry that does not read back (cut short, another format) is built again and
    /// replaced. `progress` hears "reused …" on a hit, and why an entry was not stored.
    pub fn build_dynamic_model(
        &self,
        pair: &GearPair,
        mesh: &MeshSpec,
        options: &DynamicBuildOptions,
        progress: impl Fn(String) + Sync,
    ) -> Result<(PmorModel, DynamicBuildReport), String> {
        let entry = self.entry(pair, mesh, options);
        if let Some(stored) = std::fs::read(&entry).ok().and_then(|bytes| Self::read_back(&bytes)) {
            progress(format!("reused from the build cache ({})", entry.display()));
            return Ok(stored);
        }
        let built = build_dynamic_model(pair, mesh, options, &progress)?;
        // The cache only saves time: an entry not stored costs the next build, nothing else.
        if let Err(why) = self.store(&entry, &built) {
            progress(format!("not stored in the build cache ({}): {why}", entry.display()));
        }
        Ok(built)
    }

    /// An entry's bytes: the SHA-256 of the payload, then the payload (postcard). A file cut short
    /// or filled by a crash fails the digest and is never taken for a model.
    fn read_back(bytes: &[u8]) -> Option<(PmorModel, DynamicBuildReport)> {
        let (digest, payload) = bytes.split_at_checked(32)?;
        (Sha256::digest(payload).as_slice() == digest).then(|| postcard::from_bytes(payload).ok()).flatten()
    }

    /// Written beside under a name of its own (process and call), synced, then renamed: an entry
    /// is whole or absent, whoever reads it meanwhile. The entries of other code go (they can
    /// never be hit again).
    fn store(&self, entry: &Path, built: &(PmorModel, DynamicBuildReport)) -> std::io::Result<()> {
        use std::io::Write;
        static STORES: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
        std::fs::create_dir_all(&self.dir)?;
        let ours = Self::code_prefix();
        for old in std::fs::read_dir(&self.dir)?.filter_map(|e| e.ok()).map(|e| e.file_name()) {
            let name = old.to_string_lossy();
            if name.starts_with("pmor-") && name.ends_with(".postcard") && !name.starts_with(&ours) {
                std::fs::remove_file(self.dir.join(&old)).ok(); // another process may have removed it
            }
        }
        let payload = postcard::to_stdvec(built).map_err(std::io::Error::other)?;
        let call = STORES.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        let partial = entry.with_extension(format!("partial-{}-{call}", std::process::id()));
        let mut file = std::fs::OpenOptions::new().write(true).create_new(true).open(&partial)?;
        file.write_all(&Sha256::digest(&payload))?;
        file.write_all(&payload)?;
        file.sync_all()?;
        std::fs::rename(&partial, entry)
    }
}

/// `build_dynamic_model` through the cache `GEARFMU_BUILD_CACHE` names, where it is set.
pub fn build_dynamic_model_reusing(
    pair: &GearPair,
    mesh: &MeshSpec,
    options: &DynamicBuildOptions,
    progress: impl Fn(String) + Sync,
) -> Result<(PmorModel, DynamicBuildReport), String> {
    match BuildCache::from_env() {
        Some(cache) => cache.build_dynamic_model(pair, mesh, options, progress),
        None => build_dynamic_model(pair, mesh, options, progress),
    }
}
