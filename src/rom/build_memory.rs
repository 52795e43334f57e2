//! The offline build's peak memory, estimated before the FE stage (issue 40): from the sizes the
//! build knows once each gear is meshed, assembled and its factor analysed — DOFs, non-zeros of
//! K and of the Cholesky factor L, flank nodes, modes, shapes — and the arrays each stage holds.
//! Memory is a limit, not a hope: a build that will not fit runs the two gears one after the
//! other, and one that will not fit that way is refused with the figure, before the expensive
//! part starts.

use serde::{Deserialize, Serialize};

/// What one gear's FE stage will hold, in counts (all known before its factorization).
#[derive(Debug, Clone, Copy)]
pub struct GearSizes {
    /// Free DOFs n (the bore clamped) and all DOFs N.
    pub free_dofs: usize,
    pub all_dofs: usize,
    /// Non-zeros of K over the free DOFs (the consistent mass has K's pattern).
    pub stiffness_nnz: usize,
    /// Non-zeros of the Cholesky factors the gear holds (the whole gear's L, or every
    /// harmonic's: `fe::cyclic_symmetry`), and the numeric factorization's work space (bytes).
    pub factor_nnz: usize,
    pub factorization_scratch_bytes: usize,
    /// Non-zeros of the Sturm check's LDLᵀ factors held at once (the whole gear's, as many as
    /// L; or the largest harmonic's, one per thread) and of the harmonics' K_h and M_h (none
    /// for the whole gear).
    pub sturm_factor_nnz: usize,
    pub harmonic_matrix_nnz: usize,
    /// Hexahedra.
    pub elements: usize,
    /// Columns of ψ (loadable flank nodes) and of those solved (one tooth's).
    pub attachment_columns: usize,
    pub solved_columns: usize,
    /// Entries of the eigen solver's arrays held at once besides the modes: the Krylov space
    /// (V, KV, MV; by harmonics one space per thread and the whole modes' K and M products).
    pub krylov_entries: usize,
    pub probed_modes: usize,
    /// Fields the shapes stage holds at once (samples × shapes, Φ, and their mass products).
    pub shape_fields: usize,
}

const F64: f64 = 8.0;
/// A sparse matrix entry: its value and its row index.
const SPARSE_ENTRY: f64 = 16.0;

/// One gear's share of the peak (bytes).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GearMemory {
    /// The highest the gear's FE stage (factor, eigenmodes, attachment modes) reaches.
    pub fe_stage_peak: f64,
    /// What it keeps afterwards until its shapes are made (K, the reduction basis, Φ).
    pub kept: f64,
    /// What it keeps after its shapes (Φ).
    pub kept_after_shapes: f64,
    /// Its shapes stage on top of what it kept (the full mass and the fields).
    pub shapes_stage: f64,
}

impl GearSizes {
    pub fn memory(&self) -> GearMemory {
        let (n, big_n) = (self.free_dofs as f64, self.all_dofs as f64);
        let stiffness = SPARSE_ENTRY * self.stiffness_nnz as f64;
        // The mass over the free DOFs has K's pattern; the full mass over all DOFs is K's
        // pattern grown by the bore's rows and columns.
        let mass = stiffness;
        let full_mass = stiffness * big_n / n;
        let factor = F64 * self.factor_nnz as f64;
        let scratch = self.factorization_scratch_bytes as f64;
        // The mass is assembled with K and L held: its pattern, values and one chunk of element
        // matrices (`fe::assembly`).
        let assembly = mass + F64 * 576.0 * 4096.0;
        let basis = F64 * n * self.attachment_columns as f64;
        let modes = F64 * n * self.probed_modes as f64;
        // Eigen stage: the free mass, the Krylov space, then — the space freed — the Sturm
        // LDLᵀ with its work space.
        let sturm = F64 * self.sturm_factor_nnz as f64 + scratch;
        let eigen = mass + modes + (F64 * self.krylov_entries as f64).max(sturm);
        // Attachment stage: ψ and the solved tooth's columns, with the work space of their solve
        // (the harmonics' coefficients of as many columns); K_r comes from the cuts' reactions,
        // with no product of K and ψ (`rom::attachment::GlobalAttachmentModes`).
        let attachment = modes + basis + 2.0 * F64 * n * self.solved_columns as f64;
        let phi = F64 * big_n * self.probed_modes as f64;
        GearMemory {
            fe_stage_peak: stiffness
                + SPARSE_ENTRY * self.harmonic_matrix_nnz as f64
                + factor
                + eigen.max(attachment).max(scratch).max(assembly),
            kept: stiffness + basis + phi,
            kept_after_shapes: phi,
            shapes_stage: full_mass + F64 * big_n * self.shape_fields as f64,
        }
    }
}

/// How the two gears' FE stages run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Schedule {
    /// Side by side (`rayon::join`): the faster, the peaks add up.
    SideBySide,
    /// Gear 1, then gear 2: the peak is one gear's stage plus what the other keeps.
    OneAfterTheOther,
}

/// The build's estimated peak (bytes) under each schedule.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BuildMemory {
    pub gears: [GearMemory; 2],
}

/// What the process holds besides the gears' arrays (the binary, the meshes, the statics).
pub const BASE_BYTES: f64 = 0.3e9;

impl BuildMemory {
    pub fn peak(&self, schedule: Schedule) -> f64 {
        let [a, b] = self.gears;
        let fe = match schedule {
            Schedule::SideBySide => a.fe_stage_peak + b.fe_stage_peak,
            Schedule::OneAfterTheOther => a.fe_stage_peak.max(a.kept + b.fe_stage_peak),
        };
        // Gear 1's shapes, then gear 2's: each frees its K and basis when done.
        let shapes = (a.kept + a.shapes_stage + b.kept).max(a.kept_after_shapes + b.kept + b.shapes_stage);
        BASE_BYTES + fe.max(shapes)
    }

    /// The faster schedule that fits `limit_bytes`, or why none does.
    pub fn schedule(&self, limit_bytes: f64) -> Result<Schedule, String> {
        for schedule in [Schedule::SideBySide, Schedule::OneAfterTheOther] {
            if self.peak(schedule) <= limit_bytes {
                return Ok(schedule);
            }
        }
        Err(format!(
            "the build needs an estimated {:.1} GB (gears one after the other; {:.1} GB side by side) and may take {:.1} GB \
             (--memory-limit-gb, else the machine's available memory): \
             mesh coarser (a [mesh] section with fewer elements_across_tooth, elements_in_rim or axial_slices; the default is \
             10/10/10 and the slices the helix needs), or raise the limit with --memory-limit-gb if memory will be freed",
            self.peak(Schedule::OneAfterTheOther) / 1e9,
            self.peak(Schedule::SideBySide) / 1e9,
            limit_bytes / 1e9
        ))
    }
}

/// Memory this process may take (bytes): `MemAvailable` of /proc/meminfo (Linux); `None` where
/// the system does not tell (then the build does not refuse).
pub fn available_bytes() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn gear(scale: usize) -> GearSizes {
        GearSizes {
            free_dofs: 100_000 * scale,
            all_dofs: 101_000 * scale,
            stiffness_nnz: 8_000_000 * scale,
            factor_nnz: 40_000_000 * scale,
            factorization_scratch_bytes: 50_000_000 * scale,
            elements: 30_000 * scale,
            attachment_columns: 400,
            solved_columns: 100,
            sturm_factor_nnz: 40_000_000 * scale,
            harmonic_matrix_nnz: 0,
            krylov_entries: 3 * 188 * 100_000 * scale,
            probed_modes: 26,
            shape_fields: 440,
        }
    }

    /// The schedule: side by side where both fit, one after the other where only that fits, a
    /// refusal naming the figure and the option otherwise; one after the other never needs more.
    #[test]
    fn the_schedule_is_the_fastest_that_fits_and_the_refusal_names_the_figure() {
        let build = BuildMemory { gears: [gear(1).memory(), gear(2).memory()] };
        let (side, one) = (build.peak(Schedule::SideBySide), build.peak(Schedule::OneAfterTheOther));
        assert!(one < side, "one after the other {one:e} < side by side {side:e}");
        assert_eq!(build.schedule(side * 1.01), Ok(Schedule::SideBySide));
        assert_eq!(build.schedule(0.5 * (one + side)), Ok(Schedule::OneAfterTheOther));
        let refusal = build.schedule(0.9 * one).unwrap_err();
        assert!(
            refusal.contains(&format!("{:.1} GB", one / 1e9)) && refusal.contains("--memory-limit-gb"),
            "{refusal}"
        );
    }
}
