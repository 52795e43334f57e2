//! The reduction space of PMOR-Hertz (paper Sect. 4.2, Algorithm 1) on the spur pinion: global
//! attachment modes per loadable flank node (one flank of three consecutive teeth), then SVD
//! compression. References: the global response to a line load at the pitch point computed
//! directly (total − its own partial model), against the Galerkin compliance fᵀψ(ψᵀKψ)⁻¹ψᵀf in
//! (a) all global attachment modes — superposition of per-node modes — and (b) the compressed
//! space at several p_en.

mod common;

use faer::Mat;
use gearfmu::fe::assembly::{self, Cholesky};
use gearfmu::fe::clamped_gear::ClampedGear;
use gearfmu::fe::hex8::Formulation;
use gearfmu::fe::tooth_stiffness::pitch_line_load;
use gearfmu::rom::attachment::{global_attachment_modes, total_and_global_response};
use gearfmu::rom::svd::compress;

#[test]
fn compressed_global_attachment_space_carries_the_line_load() {
    let (p, spec) = (common::kurokawa_spur(), common::medium_mesh(4));
    let depth = 3e-3;
    let model = ClampedGear::new(&p, &p.gear1, &spec, Formulation::IncompatibleModes);
    let (gm, dofs, material, k) = (&model.mesh, &model.dofs, &model.material, &model.stiffness);
    let chol = Cholesky::new(k).unwrap();
    let teeth = [gm.teeth - 1, 0, 1];
    let nodes: Vec<(usize, [f64; 3])> =
        gm.flank_nodes.iter().filter(|f| f.side == 1 && teeth.contains(&f.tooth)).map(|f| (f.node, f.normal)).collect();
    let modes = global_attachment_modes(
        &gm.mesh,
        &material,
        Formulation::IncompatibleModes,
        &dofs,
        &chol,
        &nodes,
        depth,
        |_| {},
    )
    .unwrap();
    let psi = &modes.psi;

    let load = pitch_line_load(gm, &p.gear1, spec.axial_slices, 1000.0).unwrap();
    let f = dofs.load_vector(&load);
    let (_, global) =
        total_and_global_response(&gm.mesh, material, Formulation::IncompatibleModes, dofs, &chol, &load, depth)
            .unwrap();
    let direct: f64 = dofs.free.iter().enumerate().filter_map(|(d, free)| free.map(|i| f[i] * global[d])).sum();
    let galerkin = |b: &Mat<f64>| {
        let n = b.ncols();
        let mut kb = Mat::zeros(dofs.n_free, n);
        for j in 0..n {
            let col: Vec<f64> = (0..dofs.n_free).map(|i| b[(i, j)]).collect();
            for (i, v) in assembly::mul(k, &col).into_iter().enumerate() {
                kb[(i, j)] = v;
            }
        }
        let kr = b.transpose() * &kb;
        let kr = nalgebra::DMatrix::from_fn(n, n, |i, j| kr[(i, j)]);
        let bf = nalgebra::DVector::from_fn(n, |j, _| (0..dofs.n_free).map(|i| b[(i, j)] * f[i]).sum());
        bf.dot(&kr.svd(true, true).solve(&bf, 1e-14).unwrap())
    };
    let full = galerkin(psi);
    let error_full = (full - direct) / direct;
    println!(
        "n_c = {}: direct global line compliance {direct:.5e}, Galerkin in ψ_glob {full:.5e} ({:+.3} %)",
        nodes.len(),
        100.0 * error_full
    );
    assert!(error_full.abs() < 0.01, "per-node global modes must superpose to the line load's global response");

    let mut previous_error = f64::INFINITY;
    for p_en in [0.99, 0.999, 0.9999] {
        let c = compress(&modes.reduced_stiffness(dofs), psi.clone(), p_en);
        let reduced = galerkin(&c.basis);
        let error = (reduced - full) / full;
        println!(
            "p_en {p_en}: n_sv {} of {} (retained {:.5}), compliance {:+.2} % against ψ_glob",
            c.n_sv,
            nodes.len(),
            c.retained,
            100.0 * error
        );
        // A subspace of ψ_glob can only be stiffer (Galerkin), and more vectors can only help.
        assert!(error <= 1e-9 && error.abs() <= previous_error + 1e-9);
        previous_error = error.abs();
        assert!(c.n_sv < nodes.len() / 2, "the compression should compress");
    }
    assert!(previous_error < 0.02, "at p_en = 99.99 % the line load's compliance should be within 2 %");
}
