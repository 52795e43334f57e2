//! The FE model's views: `mesh` (VTK, PNG), `modes` (eigenmodes) and `tooth-stiffness`.

use anyhow::Result;
use gearfmu::closed_forms::iso6336;
use gearfmu::fe::clamped_gear::ClampedGear;
use gearfmu::fe::gear_mesh::{mesh_gear, GearMesh};
use gearfmu::fe::hex8::Formulation;
use gearfmu::fe::{eigen, vtk};
use std::path::{Path, PathBuf};

use crate::cli::{pair_and_mesh, Resolution};

use crate::progress::spinner;

pub(crate) fn output_path(stem: &Path, gear: usize, extension: &str) -> PathBuf {
    let name = format!("{}_gear{gear}.{extension}", stem.file_stem().and_then(|s| s.to_str()).unwrap_or("gear"));
    stem.with_file_name(name)
}

pub(crate) fn node_sets(gm: &GearMesh) -> Vec<(&'static str, Vec<i32>)> {
    let n = gm.mesh.nodes.len();
    let mut bore = vec![0; n];
    for &b in &gm.bore_nodes {
        bore[b] = 1;
    }
    let (mut side, mut tooth) = (vec![0; n], vec![-1; n]);
    for f in &gm.flank_nodes {
        side[f.node] = f.side as i32;
        tooth[f.node] = f.tooth as i32;
    }
    vec![("bore", bore), ("flank_side", side), ("flank_tooth", tooth)]
}

pub(crate) fn mesh_command(
    spec: &Path,
    resolution: Resolution,
    vtk: Option<PathBuf>,
    png: Option<PathBuf>,
) -> Result<()> {
    let (pair, mesh_spec) = pair_and_mesh(spec, resolution)?;
    for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
        let bar = spinner(format!("meshing gear {}", i + 1));
        let gm = mesh_gear(&pair, gear, &mesh_spec);
        bar.finish_and_clear();
        let free = 3 * (gm.mesh.nodes.len() - gm.bore_nodes.len());
        println!(
            "gear {} (z = {}): {} nodes, {} elements, {} DOFs ({} free with the bore clamped), {} flank nodes",
            i + 1,
            gear.teeth,
            gm.mesh.nodes.len(),
            gm.mesh.elements.len(),
            gm.mesh.dofs(),
            free,
            gm.flank_nodes.len()
        );
        if let Some(stem) = &vtk {
            let path = output_path(stem, i + 1, "vtu");
            vtk::write_vtu(&path, &gm.mesh, &node_sets(&gm), &[])?;
            println!("  wrote {}", path.display());
        }
        if let Some(stem) = &png {
            let path = output_path(stem, i + 1, "png");
            gearfmu::fe::profile_png::write_profile_png(&path, &pair, gear, &gm).map_err(anyhow::Error::msg)?;
            println!("  wrote {}", path.display());
        }
    }
    Ok(())
}

pub(crate) fn modes_command(
    spec: &Path,
    count: usize,
    resolution: Resolution,
    vtk: Option<PathBuf>,
    whole_gear: bool,
) -> Result<()> {
    use gearfmu::fe::cyclic_symmetry::CyclicGear;
    let (pair, mesh_spec) = pair_and_mesh(spec, resolution)?;
    for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
        let bar = spinner(format!("gear {}: meshing and assembling", i + 1));
        let model = ClampedGear::new(&pair, gear, &mesh_spec, Formulation::IncompatibleModes);
        let (gm, dofs, k, m) = (&model.mesh, &model.dofs, &model.stiffness, model.mass());
        let cyclic = if whole_gear { None } else { CyclicGear::new(&model).map_err(anyhow::Error::msg)? };
        let (modes, solver) = match cyclic {
            Some(cyclic) => {
                bar.set_message(format!("gear {}: {} harmonics ({} DOFs)", i + 1, cyclic.harmonics(), dofs.n_free));
                let (harmonics, edge, sector) = (cyclic.harmonics(), cyclic.edge_dofs(), cyclic.sector_dofs());
                let factored = cyclic.factorize().map_err(anyhow::Error::msg)?;
                let modes = factored.lowest_modes(k, &m, count, 1e-10, 300).map_err(anyhow::Error::msg)?;
                (modes, format!("by {harmonics} harmonics, sectors of {sector} DOFs with edges of {edge}"))
            }
            None => {
                bar.set_message(format!("gear {}: block Lanczos ({} DOFs)", i + 1, dofs.n_free));
                let chol = model.factorize().map_err(anyhow::Error::msg)?;
                let modes = eigen::lowest_modes_factored(k, &m, &chol, count, 1e-10, 300, |it, converged| {
                    bar.set_message(format!("gear {}: block Lanczos step {it}, {converged}/{count} converged", i + 1))
                })
                .map_err(anyhow::Error::msg)?;
                (
                    modes,
                    format!("whole gear, {:.1} M non-zeros in K's Cholesky factor", chol.factor_nnz() as f64 * 1e-6),
                )
            }
        };
        bar.finish_and_clear();
        println!(
            "gear {} (z = {}, {} DOFs, {solver}): {} block steps; Sturm count below the shift {} = Ritz values below it {}{}",
            i + 1,
            gear.teeth,
            dofs.n_free,
            modes.iterations,
            modes.sturm_count,
            modes.ritz_values_below_shift,
            if modes.sturm_count == modes.ritz_values_below_shift {
                " (no mode missed)"
            } else {
                " — A MODE WAS MISSED"
            }
        );
        for (j, (f, r)) in modes.frequencies_hz().iter().zip(&modes.residuals).enumerate() {
            println!("  mode {:>3}: {:>14.4} Hz   residual {:.1e}", j + 1, f, r);
        }
        if let Some(stem) = &vtk {
            let shapes: Vec<Vec<f64>> = (0..count)
                .map(|c| dofs.expand(&(0..dofs.n_free).map(|r| modes.vectors[(r, c)]).collect::<Vec<_>>()))
                .collect();
            let names: Vec<String> = (0..count).map(|c| format!("mode_{}", c + 1)).collect();
            let fields: Vec<vtk::NodeField> =
                shapes.iter().zip(&names).map(|(v, n)| vtk::NodeField { name: n, components: 3, values: v }).collect();
            let path = output_path(stem, i + 1, "vtu");
            vtk::write_vtu(&path, &gm.mesh, &node_sets(gm), &fields)?;
            println!("  wrote {}", path.display());
        }
    }
    Ok(())
}

pub(crate) fn tooth_stiffness_command(spec: &Path, resolution: Resolution) -> Result<()> {
    let (pair, mesh_spec) = pair_and_mesh(spec, resolution)?;
    let mut pair_compliance = 0.0;
    for (i, gear) in [&pair.gear1, &pair.gear2].into_iter().enumerate() {
        let bar = spinner(format!("gear {}: mesh, assembly, Cholesky", i + 1));
        let fe = gearfmu::fe::tooth_stiffness::single_tooth_compliance(
            &pair,
            gear,
            &mesh_spec,
            Formulation::IncompatibleModes,
        )
        .map_err(anyhow::Error::msg)?;
        bar.finish_and_clear();
        let pem = gearfmu::closed_forms::mesh_stiffness::tooth_compliance_per_width(
            gear,
            &pair,
            gear.pitch_radius_m,
            pair.youngs_modulus_pa,
            pair.poisson_ratio,
        );
        println!(
            "gear {} (z = {}, {} DOF): FE {:.5} mm·µm/N, potential energy {:.5} mm·µm/N (FE/PEM {:.3})",
            i + 1,
            gear.teeth,
            fe.dofs,
            fe.compliance_per_width * 1e9,
            pem * 1e9,
            fe.compliance_per_width / pem
        );
        pair_compliance += fe.compliance_per_width * 1e9;
    }
    let c = 1.0 / pair_compliance;
    // The q′ series is for steel (E_st = 206 GPa): compare at the pair's own modulus.
    let c_th = iso6336::theoretical_single_stiffness(&pair) * iso6336::material_factor(&pair);
    println!(
        "pair: FE {c:.2} N/(mm·µm); ISO 6336-1 c′_th·E/E_st {c_th:.2} (FE/ISO {:.3}), c′ = c′_th·C_M·C_B·E/E_st {:.2} (FE/ISO {:.3})",
        c / c_th,
        iso6336::single_stiffness(&pair),
        c / iso6336::single_stiffness(&pair)
    );
    Ok(())
}
