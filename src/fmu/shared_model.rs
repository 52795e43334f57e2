//! Instances of one FMU in one process share its model data.
//!
//! A master that instantiates an FMU several times (a drivetrain with two stages of the same
//! pair, a sweep's worker resetting one instance per point, a fuzzer) would otherwise read,
//! checksum and decode the same model file once per instance: megabytes and milliseconds each
//! time for the PMOR-Hertz model. The data is immutable once loaded, so instances can hold one
//! `Arc` of it.
//!
//! The key is the file's *content*, compared byte for byte, not its path or timestamps: a file
//! rewritten in place within the file system's timestamp granularity, or edited by a hostile
//! hand, is a different key and goes through the full check (magic, version, SHA-256, decode,
//! model checks) again. Only bytes identical to bytes that passed that check reuse its result.
//! An entry lives while an instance holds it (a `Weak`), so freeing the last instance frees the
//! model.

use std::sync::{Arc, Mutex, Weak};

pub struct SharedByContent<T> {
    /// (the file's bytes, the model decoded from exactly those bytes).
    entries: Mutex<Vec<(Vec<u8>, Weak<T>)>>,
}

impl<T> SharedByContent<T> {
    pub const fn new() -> Self {
        SharedByContent { entries: Mutex::new(Vec::new()) }
    }

    /// The model decoded from `bytes`: the one a live instance already holds if its file had
    /// exactly these bytes, else `load(&bytes)` (kept for the next instance if it succeeds).
    /// The lock is held while loading, so two threads instantiating the same FMU decode it once.
    pub fn get_or_load(&self, bytes: Vec<u8>, load: impl FnOnce(&[u8]) -> Result<T, String>) -> Result<Arc<T>, String> {
        // A panic while loading (caught by the FMI guard) leaves the list consistent: entries are
        // only pushed or dropped whole, so a poisoned lock is still safe to use.
        let mut entries = self.entries.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        entries.retain(|(_, model)| model.strong_count() > 0);
        if let Some(model) = entries.iter().find(|(b, _)| *b == bytes).and_then(|(_, model)| model.upgrade()) {
            return Ok(model);
        }
        let model = Arc::new(load(&bytes)?);
        entries.push((bytes, Arc::downgrade(&model)));
        Ok(model)
    }
}

impl<T> Default for SharedByContent<T> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::cell::Cell;

    #[test]
    fn identical_bytes_share_one_model_while_an_instance_holds_it() {
        let cache = SharedByContent::<String>::new();
        let loads = Cell::new(0);
        let load = |b: &[u8]| {
            loads.set(loads.get() + 1);
            Ok(String::from_utf8_lossy(b).into_owned())
        };
        let a = cache.get_or_load(b"model".to_vec(), load).unwrap();
        let b = cache.get_or_load(b"model".to_vec(), load).unwrap();
        assert!(Arc::ptr_eq(&a, &b));
        assert_eq!(loads.get(), 1);
        // One byte different: a different file, loaded and checked again.
        let c = cache.get_or_load(b"modeL".to_vec(), load).unwrap();
        assert_eq!((c.as_str(), loads.get()), ("modeL", 2));
        // Once no instance holds it, the model is freed and the next instance loads it again.
        drop((a, b));
        let _d = cache.get_or_load(b"model".to_vec(), load).unwrap();
        assert_eq!(loads.get(), 3);
    }

    #[test]
    fn a_refused_file_is_not_kept() {
        let cache = SharedByContent::<String>::new();
        let e = cache.get_or_load(b"bad".to_vec(), |_| Err("checksum mismatch".to_string())).unwrap_err();
        assert_eq!(e, "checksum mismatch");
        assert!(cache.entries.lock().unwrap().is_empty());
    }
}
