//! Nested-dissection ordering (METIS) against AMD on the same gear: the same solution to round-off,
//! and the fill of each reported; and reuse of the symbolic factorization on a matrix with the
//! same pattern (2K must give half the displacement, a closed form).

mod common;

use faer::sparse::{SparseColMat, Triplet};
use gearfmu::fe::assembly::{relative_residual, Cholesky};
use gearfmu::fe::clamped_gear::ClampedGear;
use gearfmu::fe::hex8::Formulation;
use gearfmu::fe::tooth_stiffness::pitch_line_load;

#[test]
fn nested_dissection_factor_solves_like_amd_and_symbolic_reuse_works() {
    let (p, spec) = (common::kurokawa_spur(), common::medium_mesh(6));
    let model = ClampedGear::new(&p, &p.gear1, &spec, Formulation::IncompatibleModes);
    let k = &model.stiffness;
    let f = model.dofs.load_vector(&pitch_line_load(&model.mesh, &p.gear1, spec.axial_slices, 1000.0).unwrap());
    let amd = Cholesky::new(k).unwrap();
    let nd = model.factorize().unwrap();
    let (u_amd, u_nd) = (amd.solve(&f), nd.solve(&f));
    let scale = u_amd.iter().map(|v| v.abs()).fold(0.0, f64::max);
    let diff = u_amd.iter().zip(&u_nd).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max) / scale;
    println!(
        "{} DOF: nnz(L) AMD {:.3e}, nested dissection {:.3e} (ratio {:.2}); solutions differ by {diff:.1e}",
        model.dofs.n_free,
        amd.factor_nnz() as f64,
        nd.factor_nnz() as f64,
        nd.factor_nnz() as f64 / amd.factor_nnz() as f64
    );
    assert!(relative_residual(k, &u_nd, &f) < 1e-10);
    assert!(diff < 1e-9);
    // Same pattern, doubled values: the reused symbolic factorization must give u/2.
    let a = k.as_ref();
    let mut triplets = Vec::new();
    for j in 0..k.ncols() {
        for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            triplets.push(Triplet::new(i, j, 2.0 * v));
        }
    }
    let k2 = SparseColMat::try_new_from_triplets(k.nrows(), k.ncols(), &triplets).unwrap();
    let u_half = nd.refactor(&k2).unwrap().solve(&f);
    let err = u_half.iter().zip(&u_nd).map(|(h, u)| (h - 0.5 * u).abs()).fold(0.0, f64::max) / scale;
    assert!(err < 1e-12, "{err}");
}
