//! fmu-build: turns a gear-pair spec into an FMI 2.0 Co-Simulation FMU, and inspects models.
//!
//! `fmu-build build examples/kurokawa_spur.toml -o KurokawaSpur.fmu [--model lumped]`
//! `fmu-build inspect examples/kurokawa_spur.toml [--json mesh.json]`
//! `fmu-build mesh examples/kurokawa_spur.toml [--vtk out/spur] [--png out/spur] [--across N --profile N --rim N --slices N]`
//! `fmu-build modes examples/kurokawa_spur.toml -n 10 [--vtk out/spur]`
//! `fmu-build tooth-stiffness examples/kurokawa_spur.toml [--across N --profile N --rim N --slices N]`
//! `fmu-build element shaft -o Shaft.fmu --stiffness-nm-per-rad 2e4` (inertia, shaft, motor, load)
//! `fmu-build ssp --gear-fmu KurokawaSpur.fmu -o drivetrain.ssp` (motor → shaft → gear pair → shaft → load)

mod build_command;
mod cli;
mod cli_values;
mod drivetrain;
mod fe_views;
mod fmu_archive;
mod inspect;
mod linearize;
mod model_description;
mod progress;
mod ste;

use clap::Parser;
use cli::{Cli, Command};

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Build { spec, output, model, mesh_law, lumped_fmu, library, rom, resolution } => {
            build_command::build(&spec, &output, model, mesh_law, lumped_fmu.as_deref(), library, &rom, resolution)
        }
        Command::Inspect { spec, json, mesh_law, from_fmu, resolution } => {
            inspect::inspect(&spec, json, mesh_law, from_fmu.as_deref(), resolution)
        }
        Command::Mesh { spec, resolution, vtk, png } => fe_views::mesh_command(&spec, resolution, vtk, png),
        Command::ToothStiffness { spec, resolution } => fe_views::tooth_stiffness_command(&spec, resolution),
        Command::Modes { spec, count, resolution, vtk, whole_gear } => {
            fe_views::modes_command(&spec, count, resolution, vtk, whole_gear)
        }
        Command::Linearize { fmu, torque_nm, mesh_damping_ratio, positions, count } => {
            linearize::linearize_command(&fmu, torque_nm, mesh_damping_ratio, positions, count)
        }
        Command::Element { kind, output, name, options, library } => {
            drivetrain::element_command(kind, &output, name, &options, library)
        }
        Command::Ssp { gear_fmu, output, options, library } => {
            drivetrain::ssp_command(&gear_fmu, &output, &options, library)
        }
        Command::Ste {
            spec,
            torque_nm,
            angles,
            pitches,
            method,
            depth_mm,
            p_en,
            eq20,
            friction,
            resolution,
            csv,
            png,
        } => {
            let options = ste::SteOptions { torque_nm, angles, pitches, method, depth_mm, p_en, eq20, friction };
            ste::ste_with_defaults(&spec, options, resolution, ste::StePlots { csv, png })
        }
    };
    if let Err(e) = result {
        eprintln!("fmu-build: error: {e:#}");
        std::process::exit(1);
    }
}
