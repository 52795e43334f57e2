//! Finite element costs for the Kurokawa spur gears (`cargo bench --bench fe`), at the default
//! coarse mesh and near the paper's resolution (≈130 k DOF per gear): mesh, assembly,
//! factorization (time, nnz(L)), a block of 64 solves, the lowest 40 eigenpairs, peak memory.
//! Set GEARFMU_BENCH_FINE=0 to skip the fine mesh.

use faer::Mat;
use gearfmu::fe::assembly::Cholesky;
use gearfmu::fe::clamped_gear::ClampedGear;
use gearfmu::fe::eigen::lowest_modes_factored;
use gearfmu::fe::gear_mesh::MeshSpec;
use gearfmu::fe::hex8::Formulation;
use gearfmu::gear::{GearPair, PairSpec};
use std::time::Instant;

fn peak_memory_mib() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM"))
                .map(|l| l.split_whitespace().nth(1).unwrap().parse::<f64>().unwrap())
        })
        .map_or(f64::NAN, |kib| kib / 1024.0)
}

fn main() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/kurokawa_spur.toml");
    let pair = GearPair::from_spec(&PairSpec::load(&path).unwrap()).unwrap();
    let mut levels = vec![("default", MeshSpec::default())];
    if std::env::var("GEARFMU_BENCH_FINE").map_or(true, |v| v != "0") {
        levels.push((
            "paper-like",
            MeshSpec {
                elements_across_tooth: 8,
                elements_along_profile: 16,
                elements_in_rim: 8,
                axial_slices: 8,
                ..Default::default()
            },
        ));
    }
    println!("| mesh | gear | free DOF | mesh s | assembly K+M s | factorization AMD s / ND s | nnz(L) AMD / ND | s per block of 64 solves (2 blocks in parallel) | 40 modes s (iterations) | Sturm / Ritz below σ | peak MiB |");
    println!("|---|---|---|---|---|---|---|---|---|---|---|");
    for (name, spec) in levels {
        for (g, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
            // Mesh and assembly are timed apart: the mesher alone, then ClampedGear (mesh + K) and M.
            let t = Instant::now();
            let _ = gearfmu::fe::gear_mesh::mesh_gear(&pair, gear, &spec);
            let t_mesh = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let model = ClampedGear::new(&pair, gear, &spec, Formulation::IncompatibleModes);
            let m = model.mass();
            let (k, dofs) = (&model.stiffness, &model.dofs);
            let t_assembly = t.elapsed().as_secs_f64();
            let t = Instant::now();
            let amd = Cholesky::new(k).unwrap();
            let t_amd = t.elapsed().as_secs_f64();
            let nnz_amd = amd.factor_nnz();
            drop(amd);
            let t = Instant::now();
            let chol = model.factorize().unwrap();
            let t_factor = t.elapsed().as_secs_f64();
            let nnz_l = chol.factor_nnz();
            // Two blocks of 64 right-hand sides, solved in parallel (one per core): time per block.
            let mut rhs = Mat::from_fn(dofs.n_free, 128, |i, j| ((i * 31 + j * 17) % 101) as f64 - 50.0);
            let t = Instant::now();
            chol.solve_block(&mut rhs);
            let t_solve = t.elapsed().as_secs_f64() / 2.0;
            let t = Instant::now();
            let modes = lowest_modes_factored(k, &m, &chol, 40, 1e-8, 300, |it, c| {
                eprint!("\r{name} gear {}: iteration {it}, {c}/40 converged   ", g + 1)
            })
            .unwrap();
            eprintln!();
            let t_modes = t.elapsed().as_secs_f64();
            println!(
                "| {name} | {} (z {}) | {} | {t_mesh:.2} | {t_assembly:.2} | {t_amd:.2} / {t_factor:.2} | {:.2e} / {:.2e} | {t_solve:.2} | {t_modes:.1} ({}) | {} | {:.0} |",
                g + 1,
                gear.teeth,
                dofs.n_free,
                nnz_amd as f64,
                nnz_l as f64,
                modes.iterations,
                format!("{}/{}", modes.sturm_count, modes.ritz_values_below_shift),
                peak_memory_mib()
            );
        }
    }
}
